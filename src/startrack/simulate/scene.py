"""Scene assembly: stars (ICRS vectors + magnitudes) and an attitude in, an image and its truth out.

The pipeline is the one of seed 000 Ch. 7 (notes ``seed-000.md`` §1.4) and of seed 001 Fig. 2.5
(notes ``seed-001-004.md`` §1.2-1.7): rotate catalog vectors into the camera frame, cull those
behind or outside the field, project with the camera model (distortion included), turn magnitudes
into electrons (:mod:`.radiometry`), draw pixel-integrated Gaussians (:mod:`.psf`) and read the
detector out with its noise (:mod:`.noise`). The renderer works on plain arrays; the catalog-based
convenience :func:`startrack.simulate.sky.simulate_frame` feeds it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError
from ..frames import random_rotations
from . import _checks
from .noise import NoiseModel, read_out
from .psf import DEFAULT_RADIUS_SIGMAS, render_gaussian_psf, stamp_radius_px
from .radiometry import SENSOR_PRESETS, Sensor

DEFAULT_SENSOR: Sensor = SENSOR_PRESETS["far-mst"]


@dataclass(frozen=True)
class Truth:
    """What a simulated image contains, brightest star first.

    Attributes
    ----------
    rot_cam_from_icrs : Rotation
        The attitude the image was rendered at.
    camera : Camera
    ids : ndarray of int64, shape (K,)
        Star identifiers (Hipparcos numbers for catalog frames) of every star that put light on
        the detector, including stars centred just outside it (see :meth:`inside`).
    x, y : ndarray, shape (K,)
        True positions in our pixel convention (0-based pixel centres, x = column).
    mag : ndarray, shape (K,)
        Magnitudes used for the radiometry.
    electrons : ndarray, shape (K,)
        Expected signal electrons of each star in the exposure (before clipping at the edge).
    vectors_icrs : ndarray, shape (K, 3)
        ICRS unit vectors of the stars as rendered.
    exposure_s : float
    sensor : Sensor
    noise : NoiseModel
    background_e : float or ndarray
        Expected sky / stray-light electrons per pixel (dark current not included).
    epoch_jyear : float or None
        Catalog epoch of the star positions, when known.
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

    def __len__(self) -> int:
        return int(self.ids.shape[0])

    def inside(self, margin_px: float = 0.0) -> NDArray[np.bool_]:
        """Mask of stars whose true position is in the image, ``margin_px`` from its edge."""
        return self.camera.in_image(self.x, self.y, margin_px=margin_px)

    @property
    def background_adu(self) -> float | NDArray[np.float64]:
        """Expected per-pixel level without stars, in ADU: (background + dark) / gain + bias."""
        det = self.sensor.detector
        electrons = self.background_e + (self.sensor.dark_e if self.noise.dark else 0.0)
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


def random_attitude(rng: np.random.Generator | int | None = None) -> Rotation:
    """A ``rot_cam_from_icrs`` drawn uniformly over SO(3)."""
    return random_rotations(None, rng)


def field_radius_rad(camera: Camera, margin_px: float = 0.0) -> float:
    """Angle from the boresight beyond which no direction can land in the image (+ a margin).

    Taken as the largest angle of the image corners and edge midpoints (distortion included),
    plus ``margin_px`` at the coarsest pixel scale and 1 % for safety; at most pi.
    """
    w, h = camera.width - 0.5, camera.height - 0.5
    xs = np.array([-0.5, w, -0.5, w, camera.cx, camera.cx, -0.5, w])
    ys = np.array([-0.5, -0.5, h, h, -0.5, h, camera.cy, camera.cy])
    v = camera.pixel_to_vector(xs, ys)
    edge = float(np.max(np.arctan2(np.hypot(v[:, 0], v[:, 1]), v[:, 2])))
    pixel = 1.0 / min(camera.fx, camera.fy)
    return min(math.pi, 1.01 * edge + margin_px * pixel)


def project_stars(camera: Camera, rot_cam_from_icrs: Rotation, vectors_icrs: NDArray[np.float64],
                  margin_px: float = 0.0
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Pixel positions of ICRS directions and which of them fall within ``margin_px`` of the image.

    Returns
    -------
    x, y : ndarray, shape (N,)
        Pixel coordinates (NaN behind the camera).
    visible : ndarray of bool, shape (N,)
        In front of the camera, inside the field radius, and at most ``margin_px`` outside the
        image edge. With ``margin_px`` = the PSF stamp radius R, these are exactly the stars whose
        stamp (R pixels around the star's nearest pixel) overlaps the image.
    """
    v_cam = rot_cam_from_icrs.apply(vectors_icrs).reshape(-1, 3)
    x, y = camera.vector_to_pixel(v_cam)
    off_axis = np.arctan2(np.hypot(v_cam[:, 0], v_cam[:, 1]), v_cam[:, 2])
    near = off_axis <= field_radius_rad(camera, margin_px)
    return x, y, near & camera.in_image(x, y, margin_px=-margin_px)


def render_stars(camera: Camera, rot_cam_from_icrs: Rotation, star_vectors_icrs: ArrayLike,
                 mags: ArrayLike, ids: ArrayLike, *, sensor: Sensor | None = None,
                 background_e: float | ArrayLike = 0.0,
                 rng: np.random.Generator | int | None = None, noise: bool | NoiseModel = True,
                 radius_sigmas: float = DEFAULT_RADIUS_SIGMAS,
                 epoch_jyear: float | None = None) -> SimulatedImage:
    """Render a star image at a known attitude.

    Parameters
    ----------
    camera : Camera
        Image size, intrinsics and distortion.
    rot_cam_from_icrs : Rotation
        A single attitude mapping ICRS vectors to the camera frame.
    star_vectors_icrs : array_like, shape (N, 3)
        ICRS unit vectors of candidate stars (any part of the sky; stars outside the field are
        dropped).
    mags : array_like, shape (N,)
        Their magnitudes, in the band of ``sensor.optics.zero_point_photons_s_m2`` (V by default).
    ids : array_like of int, shape (N,)
        Their identifiers (Hipparcos numbers), copied into the truth.
    sensor : Sensor, optional
        Optics, detector and exposure; the seed 000 FAR-MST sensor when None.
    background_e : float or array_like, shape (height, width)
        Expected sky / stray-light electrons per pixel in the exposure.
    rng : numpy.random.Generator, int or None
        Noise source; the same seed gives a bit-identical image.
    noise : bool or NoiseModel
        True: all detector effects; False: the expected image (see :class:`NoiseModel`).
    radius_sigmas : float
        PSF stamp half-width in PSF sigmas.
    epoch_jyear : float, optional
        Epoch of the star vectors, recorded in the truth.

    Returns
    -------
    SimulatedImage
        The image in ADU and the truth of every star that put light on it, brightest first.
    """
    sensor = DEFAULT_SENSOR if sensor is None else sensor
    vectors, mags, ids = star_arrays(star_vectors_icrs, mags, ids)
    rot = _single_rotation(rot_cam_from_icrs)
    margin = float(stamp_radius_px(sensor.psf_sigma_px, radius_sigmas))
    x, y, visible = project_stars(camera, rot, vectors, margin)
    order = np.flatnonzero(visible)[np.argsort(mags[visible], kind="stable")]
    electrons = sensor.electrons(mags[order])
    signal = render_gaussian_psf((camera.height, camera.width), x[order], y[order], electrons,
                                 sensor.psf_sigma_px, radius_sigmas=radius_sigmas)
    model = NoiseModel.coerce(noise)
    image = read_out(signal, sensor, background_e=background_e, noise=model, rng=rng)
    truth = Truth(rot_cam_from_icrs=rot, camera=camera, ids=ids[order], x=x[order], y=y[order],
                  mag=mags[order], electrons=electrons, vectors_icrs=vectors[order],
                  exposure_s=sensor.exposure_s, sensor=sensor, noise=model,
                  background_e=_frozen(background_e), epoch_jyear=epoch_jyear)
    return SimulatedImage(image=image, truth=truth)


def star_arrays(vectors: ArrayLike, mags: ArrayLike, ids: ArrayLike
                ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Checked arrays: finite vectors (N, 3), finite magnitudes (N,), integer ids (N,) as int64."""
    vectors = _checks.finite_array("star_vectors_icrs", vectors, (None, 3))
    n = vectors.shape[0]
    mags = _checks.finite_array("mags", mags, (n,))
    ids = np.asarray(ids)
    if ids.shape != (n,) or (n and not np.issubdtype(ids.dtype, np.integer)):
        raise InvalidInputError(
            f"ids must be an integer array of shape ({n},), got {ids.dtype} {ids.shape}")
    return vectors, mags, ids.astype(np.int64)


def _single_rotation(rot: Rotation) -> Rotation:
    if not isinstance(rot, Rotation) or not rot.single:
        raise InvalidInputError("rot_cam_from_icrs must be a single scipy Rotation (not a stack)")
    return rot


def _frozen(background_e: float | ArrayLike) -> float | NDArray[np.float64]:
    """A scalar as float, an array as a read-only copy (the truth must not change under us)."""
    arr = np.asarray(background_e, dtype=float)
    if arr.ndim == 0:
        return float(arr)
    arr = arr.copy()
    arr.flags.writeable = False
    return arr
