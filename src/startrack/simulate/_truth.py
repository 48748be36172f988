"""What a simulated frame contains: the :class:`Truth` returned with every image."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from astropy.time import Time
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ._noise import NoiseModel
from ._radiometry import Sensor
from ._rso import BrightBodyFlags


@dataclass(frozen=True)
class RSOTruth:
    """Satellites of a frame (K of them, lit or not, in the image or not).

    Attributes
    ----------
    ids : ndarray of int64, shape (K,)
    x, y : ndarray, shape (K,)
        Pixel position at the frame's mid time (NaN behind the camera).
    x_start, y_start, x_end, y_end : ndarray, shape (K,)
        Pixel positions at the start and end of the exposure (the streak's end points).
    mag : ndarray, shape (K,)
        V magnitude (inf in the Earth's shadow).
    electrons : ndarray, shape (K,)
        Expected electrons over the exposure (0 when unlit).
    range_km : ndarray, shape (K,)
    lit, rendered : ndarray of bool, shape (K,)
        Outside the Earth's shadow; put light on the detector.
    """

    ids: NDArray[np.int64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    x_start: NDArray[np.float64]
    y_start: NDArray[np.float64]
    x_end: NDArray[np.float64]
    y_end: NDArray[np.float64]
    mag: NDArray[np.float64]
    electrons: NDArray[np.float64]
    range_km: NDArray[np.float64]
    lit: NDArray[np.bool_]
    rendered: NDArray[np.bool_]

    def __len__(self) -> int:
        return int(self.ids.shape[0])


@dataclass(frozen=True)
class Truth:
    """What a simulated image contains, brightest star first.

    Attributes
    ----------
    rot_cam_from_icrs : Rotation
        The attitude at the frame's mid time (mid-exposure; with a rolling shutter, of the middle
        row), which is the time tag of the frame (Samaan 2002 eq. 6).
    camera : Camera
    ids : ndarray of int64, shape (K,)
        Star identifiers (Hipparcos numbers for catalog frames) of every star that put light on
        the detector, including stars centred just outside it (see :meth:`inside`).
    x, y : ndarray, shape (K,)
        True positions at the mid time of the star's exposure, in our pixel convention (0-based
        pixel centres, x = column).
    mag : ndarray, shape (K,)
        Magnitudes used for the radiometry.
    electrons : ndarray, shape (K,)
        Expected signal electrons of each star in the exposure (colour and vignetting included,
        before clipping at the edge).
    vectors_icrs : ndarray, shape (K, 3)
        ICRS unit vectors of the stars as rendered.
    exposure_s : float
    sensor : Sensor
    noise : NoiseModel
    background_e : float or ndarray
        Expected sky / stray-light electrons per pixel (dark current not included).
    epoch_jyear : float or None
        Catalog epoch of the star positions, when known.
    x_start, y_start, x_end, y_end : ndarray, shape (K,)
        Positions at the start and end of each star's exposure (equal to x, y at zero rate).
    b_v : ndarray, shape (K,)
        Colours used (NaN where unknown).
    rate_cam_rad_s : ndarray, shape (3,)
        Angular velocity of the camera at the mid time, camera frame, rad/s.
    rot_start, rot_end : Rotation
        Attitudes at the start and end of the exposure (of the first / last row).
    t_mid_s : float
        Mid time in seconds on the attitude profile's clock.
    time_mid : astropy.time.Time or None
        The same as an absolute time, when the scene has one.
    line_time_s : float
        Rolling-shutter row delay (0: global shutter).
    rsos : RSOTruth or None
    bright_bodies : BrightBodyFlags or None
    frame_index : int or None
        Position in a sequence.
    substeps : int
        Samples along each star's path (1 for a still frame).
    """

    rot_cam_from_icrs: Rotation
    camera: Camera
    ids: NDArray[np.int64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]
    mag: NDArray[np.float64]
    electrons: NDArray[np.float64]
    vectors_icrs: NDArray[np.float64]
    exposure_s: float
    sensor: Sensor
    noise: NoiseModel = field(default_factory=NoiseModel)
    background_e: float | NDArray[np.float64] = 0.0
    epoch_jyear: float | None = None
    # These default to None and __post_init__ fills them (the positions and attitude of a still
    # frame, no colours, no rate), so they are always set once built.
    x_start: NDArray[np.float64] = None  # type: ignore[assignment]
    y_start: NDArray[np.float64] = None  # type: ignore[assignment]
    x_end: NDArray[np.float64] = None  # type: ignore[assignment]
    y_end: NDArray[np.float64] = None  # type: ignore[assignment]
    b_v: NDArray[np.float64] = None  # type: ignore[assignment]
    rate_cam_rad_s: NDArray[np.float64] = None  # type: ignore[assignment]
    rot_start: Rotation = None
    rot_end: Rotation = None
    t_mid_s: float = 0.0
    time_mid: Time | None = None
    line_time_s: float = 0.0
    rsos: RSOTruth | None = None
    bright_bodies: BrightBodyFlags | None = None
    frame_index: int | None = None
    substeps: int = 1

    def __post_init__(self) -> None:
        defaults = {"x_start": self.x, "y_start": self.y, "x_end": self.x, "y_end": self.y,
                    "b_v": np.full(len(self.ids), np.nan), "rate_cam_rad_s": np.zeros(3)}
        for name, value in defaults.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.array(value, dtype=float))
        for name in ("rot_start", "rot_end"):
            if getattr(self, name) is None:
                object.__setattr__(self, name, self.rot_cam_from_icrs)

    def __len__(self) -> int:
        return int(self.ids.shape[0])

    def inside(self, margin_px: float = 0.0) -> NDArray[np.bool_]:
        """Mask of stars whose true position is in the image, ``margin_px`` from its edge."""
        return self.camera.in_image(self.x, self.y, margin_px=margin_px)

    @property
    def streak_length_px(self) -> NDArray[np.float64]:
        """Distance from each star's start to its end position (a chord, px)."""
        return np.hypot(self.x_end - self.x_start, self.y_end - self.y_start)

    @property
    def background_adu(self) -> float | NDArray[np.float64]:
        """Expected per-pixel level without stars, in ADU: (background + dark) / gain + bias."""
        det = self.sensor.detector
        background = self.background_e if self.noise.background else 0.0
        electrons = background + (self.sensor.dark_e if self.noise.dark else 0.0)
        return electrons / det.gain_e_per_adu + (det.bias_adu if self.noise.bias else 0.0)


@dataclass(frozen=True)
class SimulatedImage:
    """A rendered image and the truth it was rendered from.

    Attributes
    ----------
    image : ndarray, shape (height, width)
        ADU; uint16 when quantised, float64 otherwise. Indexed ``image[y, x]``.
    truth : Truth
    """

    image: NDArray
    truth: Truth
