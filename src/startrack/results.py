"""Result types that flow between the stages (DESIGN.md §1).

Every result is a frozen dataclass with fixed fields. An expected failure (too few stars, no
match) is a result whose ``status`` says so and whose ``reason`` explains it in words; it is
never an exception.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from .camera import Camera


class Status(enum.Enum):
    """Outcome of a stage."""

    OK = "ok"
    TOO_FEW_STARS = "too_few_stars"
    NO_MATCH = "no_match"
    TIMEOUT = "timeout"
    DEGENERATE = "degenerate"

    def __bool__(self) -> bool:  # ``if solution.status:`` reads as "if it worked"
        return self is Status.OK


def _empty(dtype=float) -> NDArray:
    return np.zeros(0, dtype=dtype)


@dataclass(frozen=True)
class Detections:
    """Star spots found in an image, brightest first.

    Attributes
    ----------
    x, y : ndarray, shape (N,)
        Centroids in our pixel convention (0-based pixel centres, x = column).
    flux : ndarray, shape (N,)
        Background-subtracted sum of the spot, in the image's units (ADU or electrons).
    sigma_px : ndarray, shape (N,)
        1-sigma centroid uncertainty per axis, in pixels (Huffman 2006 §4.2.2 eq. 4.2 model).
    area_px : ndarray of int, shape (N,)
        Number of pixels above the threshold.
    peak : ndarray, shape (N,)
        Highest background-subtracted pixel value.
    elongation : ndarray, shape (N,)
        Ratio of the long to the short axis of the spot's second moments (1 for round).
    background, noise : float
        Robust background level and noise (standard deviation) of the image.
    point_quality : ndarray, shape (N,), or None
        How much each spot looks like the frame's point sources (stars), in [0, 1]: 1 for a
        spot as narrow and round as the frame's stars, falling to 0 for extended spots (nebula
        knots, glow) and elongated ones (limbs, streaks among round stars). None when not
        measured (a star list, an older detector): every spot then counts as a point source.
        :attr:`is_point_source` thresholds it.
    """

    x: NDArray[np.float64] = field(default_factory=_empty)
    y: NDArray[np.float64] = field(default_factory=_empty)
    flux: NDArray[np.float64] = field(default_factory=_empty)
    sigma_px: NDArray[np.float64] = field(default_factory=_empty)
    area_px: NDArray[np.int64] = field(default_factory=lambda: _empty(np.int64))
    peak: NDArray[np.float64] = field(default_factory=_empty)
    elongation: NDArray[np.float64] = field(default_factory=_empty)
    background: float = 0.0
    noise: float = 0.0
    width: int = 0
    height: int = 0
    point_quality: NDArray[np.float64] | None = None

    POINT_SOURCE_MIN_QUALITY = 0.5
    """A spot with at least this :attr:`point_quality` counts as a point source."""

    def __len__(self) -> int:
        return int(self.x.shape[0])

    @property
    def is_point_source(self) -> NDArray[np.bool_]:
        """Shape (N,): True for spots whose :attr:`point_quality` is at least
        :attr:`POINT_SOURCE_MIN_QUALITY` (all True when it was not measured)."""
        if self.point_quality is None:
            return np.ones(len(self), dtype=bool)
        return np.asarray(self.point_quality) >= self.POINT_SOURCE_MIN_QUALITY

    def take(self, index) -> Detections:
        """A subset (or reordering) of the detections, by index array or boolean mask."""
        fields = ("x", "y", "flux", "sigma_px", "area_px", "peak", "elongation")
        quality = None if self.point_quality is None else self.point_quality[index]
        return Detections(**{k: getattr(self, k)[index] for k in fields}, background=self.background,
                          noise=self.noise, width=self.width, height=self.height, point_quality=quality)


@dataclass(frozen=True)
class StarMatches:
    """Correspondences between detections and catalog stars.

    Attributes
    ----------
    status : Status
    reason : str
        Human-readable explanation when ``status`` is not OK (empty otherwise).
    det_index : ndarray of int, shape (K,)
        Index of each matched detection in the input star list.
    hip : ndarray of int, shape (K,)
        Hipparcos number of the catalog star matched to it.
    cat_vectors : ndarray, shape (K, 3)
        ICRS unit vectors of those catalog stars (at the solve epoch).
    false_match_prob : float
        Upper bound on the probability that this identification is wrong (1.0 when none).
    """

    status: Status
    reason: str = ""
    det_index: NDArray[np.int64] = field(default_factory=lambda: _empty(np.int64))
    hip: NDArray[np.int64] = field(default_factory=lambda: _empty(np.int64))
    cat_vectors: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    false_match_prob: float = 1.0

    def __len__(self) -> int:
        return int(self.det_index.shape[0])


@dataclass(frozen=True)
class AttitudeSolution:
    """An attitude estimate, or the reason there is none.

    Attributes
    ----------
    status : Status
    reason : str
    rot_cam_from_icrs : Rotation or None
        Maps ICRS unit vectors to camera-frame vectors.
    covariance_rad2 : ndarray, shape (3, 3) or None
        Covariance of the small-angle attitude error, camera frame, in rad^2 (QUEST model,
        Huffman 2006 §6.1.3 eq. 6.36).
    ra_deg, dec_deg, roll_deg : float
        Boresight and roll in the format of :mod:`startrack.frames` (NaN when unsolved).
    fov_deg : float
        Horizontal field of view of the camera used or estimated (NaN when unsolved).
    camera : Camera or None
        The camera model the solution refers to (with the estimated focal length).
    matches : StarMatches
    residuals_arcsec : ndarray, shape (K,)
        Angle between each matched detection and its catalog star after the fit.
    false_match_prob : float
    solve_time_s : float
        Wall-clock time of the solve.
    detections : Detections or None
        The stars detected in the image (for a solve from an image); ``matches.det_index``
        indexes them. None for a solve from a star list.
    epoch_jyear : float
        Catalog epoch the stars were taken at (Julian year, TDB; NaN when not recorded).
    epoch_source : str
        Where that epoch came from: "given", an image header card ("CATEPOCH", "DATE-OBS",
        "MJD-OBS", "DateTimeOriginal") or "default" (J2000.0, nothing said when); empty when not
        recorded. See :mod:`startrack.identify._image_epoch`.
    fov_source : str
        Which field of view the solve searched last, the one it found the solution in when solved: "given"
        (``fov_deg`` or ``fov_range_deg``), "camera" (a calibrated camera), "header" (the field the
        image's EXIF or FITS header states), "default" (the default search, 3-100 deg) or "wide"
        (the search of 90-150 deg after the default found nothing); empty when not recorded. See
        :func:`startrack.solve.solve_image`.
    guided_stars : int
        How many of the matched stars were measured where the solution predicted them, after
        identification (``solve_image(guided=True)``, :mod:`startrack.identify._guided`): the
        last rows of ``detections`` and of ``matches``. 0 otherwise.
    """

    status: Status
    reason: str = ""
    rot_cam_from_icrs: Rotation | None = None
    covariance_rad2: NDArray[np.float64] | None = None
    ra_deg: float = float("nan")
    dec_deg: float = float("nan")
    roll_deg: float = float("nan")
    fov_deg: float = float("nan")
    camera: Camera | None = None
    matches: StarMatches = field(default_factory=lambda: StarMatches(status=Status.NO_MATCH))
    residuals_arcsec: NDArray[np.float64] = field(default_factory=_empty)
    false_match_prob: float = 1.0
    solve_time_s: float = 0.0
    detections: Detections | None = None
    epoch_jyear: float = float("nan")
    epoch_source: str = ""
    fov_source: str = ""
    guided_stars: int = 0

    @property
    def solved(self) -> bool:
        return self.status is Status.OK

    @property
    def quaternion_xyzw(self) -> NDArray[np.float64] | None:
        """The attitude as a scalar-last quaternion (qx, qy, qz, qw) with qw >= 0 (of the two
        signs that give the same rotation), for files and CLI output."""
        return None if self.rot_cam_from_icrs is None else self.rot_cam_from_icrs.as_quat(canonical=True)

    @property
    def sigma_cross_boresight_arcsec(self) -> float:
        """1-sigma pointing uncertainty about a cross-boresight axis (rms of x and y), arcsec."""
        if self.covariance_rad2 is None:
            return float("nan")
        return float(np.degrees(np.sqrt(0.5 * (self.covariance_rad2[0, 0] + self.covariance_rad2[1, 1]))) * 3600)

    @property
    def sigma_roll_arcsec(self) -> float:
        """1-sigma uncertainty about the boresight (roll), arcsec."""
        if self.covariance_rad2 is None:
            return float("nan")
        return float(np.degrees(np.sqrt(self.covariance_rad2[2, 2])) * 3600)
