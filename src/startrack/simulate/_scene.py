"""Scene assembly: point sources and an attitude (or an attitude profile) in, an image and its
truth out.

The pipeline is the one of Huffman 2006 Ch. 7 (Huffman 2006 Ch. 7 intro) and of Sease 2013 Fig. 2.5
(Sease 2013 Eq. 2.1–2.2, Eq. 2.13–2.19): rotate catalog vectors into the camera frame at each
sub-step of the exposure (:mod:`._motion`, :mod:`._sampling`), cull those behind or outside the
field, project with the camera model (distortion included), turn magnitudes and colours into
electrons (:mod:`._radiometry`, :mod:`._passband`) dimmed by vignetting (:mod:`._optics`), draw
pixel-integrated PSFs along each path (:mod:`._streaks`), add satellites (:mod:`._rso`) and the sky
background (:mod:`._background`), and read the detector out with its noise (:mod:`._noise`). The
renderer works on plain arrays; :func:`startrack.simulate._sky.simulate_frame` feeds it from the
catalog.

Timing: an exposure of ``sensor.exposure_s`` on the clock of the attitude profile. A single
``Rotation`` with ``rate_rad_s`` becomes a constant-rate profile whose t = 0 is the frame's mid
time, so the attitude given is the truth attitude at mid-exposure; with a profile the exposure
starts at ``FrameTiming.start_s`` (0 by default).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from astropy.time import Time, TimeDelta
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError, as_float_array, check_instance
from ..frames import boresight, random_rotations
from . import _checks
from ._background import SkyBackground
from ._motion import AttitudeProfile, ConstantRate
from ._noise import NoiseModel, read_out
from ._optics import airy_first_zero_px, airy_stamp_radius_px, psf_sigma_px, star_illumination
from ._passband import SUN_B_V
from ._psf import DEFAULT_RADIUS_SIGMAS, stamp_radius_px
from ._radiometry import SENSOR_PRESETS, Sensor
from ._rso import LinesOfSight, OrbitalScene, Snapshot
from ._sampling import FixedDirections, SourcePaths, positions, sample_sources
from ._streaks import Shutter, add_airy_paths, add_gaussian_paths
from ._truth import RSOTruth, SimulatedImage, Truth

DEFAULT_SENSOR: Sensor = SENSOR_PRESETS["far-mst"]
DEFAULT_SUBSTEP_PX: float = 0.25

@dataclass(frozen=True)
class FrameTiming:
    """When a frame is exposed and how finely motion is sampled.

    Parameters
    ----------
    start_s : float or None
        Start of the exposure (of row 0) on the attitude profile's clock, s; None centres the
        frame on t = 0.
    line_time_s : float
        Rolling shutter: delay between the starts of consecutive rows, s (0: global shutter).
    substep_px : float
        Largest motion of a source between two samples of its path, px.
    epoch : astropy.time.Time or None
        Absolute time of t = 0 (needed for satellites; recorded in the truth).
    """

    start_s: float | None = None
    line_time_s: float = 0.0
    substep_px: float = DEFAULT_SUBSTEP_PX
    epoch: Time | None = None

    def __post_init__(self) -> None:
        if self.start_s is not None and not math.isfinite(self.start_s):
            raise InvalidInputError(f"start_s must be finite seconds or None, got {self.start_s!r}")
        _checks.positive("line_time_s", self.line_time_s, allow_zero=True)
        _checks.positive("substep_px", self.substep_px)
        if self.epoch is not None and not (isinstance(self.epoch, Time) and self.epoch.isscalar):
            raise InvalidInputError("epoch must be a single astropy Time or None")

    def shutter(self, exposure_s: float, height: int) -> Shutter:
        """The row timing of a frame of ``height`` rows."""
        if self.start_s is None:
            start = -0.5 * exposure_s - 0.5 * (height - 1) * self.line_time_s
        else:
            start = self.start_s
        return Shutter(start, exposure_s, self.line_time_s)

    def time_at(self, t_s: float) -> Time | None:
        return None if self.epoch is None else self.epoch + TimeDelta(t_s, format="sec")


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


def attitude_profile(attitude: Rotation | AttitudeProfile,
                     rate_rad_s: ArrayLike | None = None) -> tuple[AttitudeProfile, bool]:
    """The profile of a Rotation (+ a constant camera-frame rate) or a profile; and whether it
    turns (False only for a constant zero rate)."""
    if isinstance(attitude, Rotation):
        if not attitude.single:
            raise InvalidInputError("rot_cam_from_icrs must be a single scipy Rotation (not a stack)")
        rate = np.zeros(3) if rate_rad_s is None else as_float_array(rate_rad_s, "rate_rad_s")
        profile = ConstantRate(attitude, rate)
        return profile, not profile.static
    if not (hasattr(attitude, "attitudes") and hasattr(attitude, "rates")):
        raise InvalidInputError("the attitude must be a single scipy Rotation or an attitude profile "
                                f"(startrack.simulate._motion), got {type(attitude).__name__}")
    if rate_rad_s is not None:
        raise InvalidInputError("rate_rad_s goes with a single Rotation; a profile has its own rates")
    return attitude, not (isinstance(attitude, ConstantRate) and attitude.static)


def render_stars(camera: Camera, rot_cam_from_icrs: Rotation | AttitudeProfile, star_vectors_icrs: ArrayLike,
                 mags: ArrayLike, ids: ArrayLike, *, sensor: Sensor | None = None,
                 background_e: float | ArrayLike = 0.0,
                 rng: np.random.Generator | int | None = None, noise: bool | NoiseModel = True,
                 radius_sigmas: float = DEFAULT_RADIUS_SIGMAS, epoch_jyear: float | None = None,
                 b_v: ArrayLike | None = None, rate_rad_s: ArrayLike | None = None,
                 timing: FrameTiming | None = None, sky_background: SkyBackground | None = None,
                 orbital: OrbitalScene | Snapshot | None = None) -> SimulatedImage:
    """Render a star image at a known attitude, or over an attitude profile.

    Parameters
    ----------
    camera : Camera
        Image size, intrinsics and distortion.
    rot_cam_from_icrs : Rotation or attitude profile
        A single attitude (at the frame's mid time) mapping ICRS vectors to the camera frame, or a
        profile from :mod:`startrack.simulate._motion`.
    star_vectors_icrs : array_like, shape (N, 3)
        ICRS unit vectors of candidate stars (any part of the sky; stars outside the field are
        dropped).
    mags : array_like, shape (N,)
        Their V magnitudes.
    ids : array_like of int, shape (N,)
        Their identifiers (Hipparcos numbers), copied into the truth.
    sensor : Sensor, optional
        Optics, detector and exposure; the Huffman 2006 FAR-MST sensor when None.
    background_e : float or array_like, shape (height, width)
        Expected extra background electrons per pixel in the exposure (added to
        ``sky_background``).
    rng : numpy.random.Generator, int or None
        Noise source; the same seed gives a bit-identical image.
    noise : bool or NoiseModel
        True: all detector effects; False: the expected image (see :class:`NoiseModel`).
    radius_sigmas : float
        Gaussian PSF stamp half-width in PSF sigmas.
    epoch_jyear : float, optional
        Epoch of the star vectors, recorded in the truth.
    b_v : array_like, shape (N,), optional
        Star colours (NaN: unknown), used when the sensor has a passband.
    rate_rad_s : array_like, shape (3,), optional
        Constant angular velocity of the camera (camera frame, rad/s) with a single Rotation.
    timing : FrameTiming, optional
        Exposure start, rolling shutter, sub-step size, absolute epoch.
    sky_background : SkyBackground, optional
        Zodiacal light and stray light.
    orbital : OrbitalScene or Snapshot, optional
        Observer, satellites, Sun and Moon (an OrbitalScene needs ``timing.epoch``; a Snapshot
        must be taken at the frame's mid time).

    Returns
    -------
    SimulatedImage
        The image in ADU and the truth of every star that put light on it, brightest first.
    """
    sensor, timing, radius_sigmas = checked_render_inputs(camera, sensor, timing, radius_sigmas)
    vectors, mags, ids = star_arrays(star_vectors_icrs, mags, ids)
    colours = _colours(b_v, len(ids))
    profile, moving = attitude_profile(rot_cam_from_icrs, rate_rad_s)
    shutter = timing.shutter(sensor.exposure_s, camera.height)
    radius = psf_radius_px(camera, sensor, radius_sigmas)
    max_off_axis = field_radius_rad(camera, radius)
    paths = sample_sources(camera, profile, shutter, FixedDirections(vectors), radius, timing.substep_px,
                           max_off_axis, moving)
    order = np.argsort(mags[paths.keep], kind="stable")
    paths = _reordered(paths, order)
    keep = paths.keep
    electrons = sensor.electrons(mags[keep], colours[keep]) * star_illumination(camera, sensor.optics,
                                                                                *optics_position(paths))
    signal = np.zeros((camera.height, camera.width))
    add_sources(signal, paths, electrons, camera, sensor, radius, shutter)
    t_mid = shutter.mid_s(camera.height)
    rot_mid = rot_cam_from_icrs if not moving and isinstance(rot_cam_from_icrs, Rotation) else \
        profile.attitudes([t_mid])[0]
    snapshot = _snapshot(orbital, timing, t_mid)
    rsos = None if snapshot is None else render_rsos(signal, camera, profile, shutter, snapshot, sensor,
                                                      radius, timing.substep_px, max_off_axis)
    background = _background(background_e, sky_background, camera, sensor)
    model = NoiseModel.coerce(noise)
    image = read_out(signal, sensor, background_e=background, noise=model, rng=rng)
    ends = profile.attitudes([shutter.start_s, shutter.start_s + shutter.exposure_s
                              + (camera.height - 1) * shutter.line_time_s])
    truth = Truth(rot_cam_from_icrs=rot_mid, camera=camera, ids=ids[keep], x=paths.mid[0], y=paths.mid[1],
                  mag=mags[keep], electrons=electrons, vectors_icrs=vectors[keep], exposure_s=sensor.exposure_s,
                  sensor=sensor, noise=model, background_e=_frozen(background), epoch_jyear=epoch_jyear,
                  x_start=paths.start[0], y_start=paths.start[1], x_end=paths.end[0], y_end=paths.end[1],
                  b_v=colours[keep], rate_cam_rad_s=profile.rates([t_mid])[0], rot_start=ends[0],
                  rot_end=ends[1], t_mid_s=t_mid, time_mid=timing.time_at(t_mid),
                  line_time_s=shutter.line_time_s, rsos=rsos,
                  bright_bodies=None if snapshot is None else snapshot.bright_bodies(boresight(rot_mid), camera),
                  substeps=int(paths.samples.x.shape[1]))
    return SimulatedImage(image=image, truth=truth)


MAX_RADIUS_SIGMAS = 50.0
"""The widest PSF stamp, in PSF sigmas (the default is 5): the stamps' cost grows with its square."""


def checked_render_inputs(camera: Camera, sensor: Sensor | None, timing: FrameTiming | None, radius_sigmas: float
                          ) -> tuple[Sensor, FrameTiming, float]:
    """The camera, sensor (None: :data:`DEFAULT_SENSOR`), timing (None: a global shutter at t = 0) and
    PSF stamp radius (sigmas, up to :data:`MAX_RADIUS_SIGMAS`) of a rendering, each checked for its
    type or range; InvalidInputError naming the first that is wrong."""
    check_instance(camera, Camera, "camera")
    sensor = DEFAULT_SENSOR if sensor is None else check_instance(sensor, Sensor, "sensor")
    timing = FrameTiming() if timing is None else check_instance(timing, FrameTiming, "timing")
    radius = _checks.positive("radius_sigmas", radius_sigmas)
    if radius > MAX_RADIUS_SIGMAS:
        raise InvalidInputError(f"radius_sigmas must be at most {MAX_RADIUS_SIGMAS:g} PSF sigmas, "
                                f"got {radius_sigmas!r}")
    return sensor, timing, radius


def optics_position(paths: SourcePaths) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Where each source's PSF width and vignetting are evaluated: its mid-exposure position, or,
    when that is not defined (the source is behind the field's edge at mid-exposure while its
    streak still reaches the image), the first defined sample of its path."""
    x, y = paths.mid
    bad = ~(np.isfinite(x) & np.isfinite(y))
    if not np.any(bad):
        return x, y
    sx, sy = paths.samples.x[bad], paths.samples.y[bad]
    first = np.argmax(np.isfinite(sx) & np.isfinite(sy), axis=1)
    rows = np.arange(first.size)
    x, y = x.copy(), y.copy()
    x[bad], y[bad] = sx[rows, first], sy[rows, first]
    return x, y


def psf_radius_px(camera: Camera, sensor: Sensor, radius_sigmas: float = DEFAULT_RADIUS_SIGMAS) -> int:
    """Half-width (px) of the PSF stamps: 5 sigma of the widest Gaussian in the field, or 5 Airy
    first-zero radii."""
    optics = sensor.optics
    if optics.psf == "airy":
        return airy_stamp_radius_px(airy_first_zero_px(optics))
    return stamp_radius_px(optics.psf_sigma_px * (1.0 + optics.field_curvature), radius_sigmas)


def add_sources(signal: NDArray[np.float64], paths: SourcePaths, electrons: NDArray, camera: Camera,
                sensor: Sensor, radius: int, shutter: Shutter) -> NDArray[np.float64]:
    """Add the light of sampled sources into ``signal`` with the sensor's PSF (in place)."""
    optics = sensor.optics
    if optics.psf == "airy":
        return add_airy_paths(signal, paths.samples, electrons, airy_first_zero_px(optics), radius, shutter)
    sigma = np.broadcast_to(psf_sigma_px(camera, optics, *optics_position(paths)), electrons.shape)
    return add_gaussian_paths(signal, paths.samples, electrons, np.ascontiguousarray(sigma), radius, shutter)


def render_rsos(signal: NDArray[np.float64], camera: Camera, profile: AttitudeProfile, shutter: Shutter,
                snapshot: Snapshot, sensor: Sensor, radius: int, substep_px: float,
                max_off_axis_rad: float) -> RSOTruth:
    """Add the lit satellites of ``snapshot`` into ``signal`` and return their truth."""
    t_mid = shutter.mid_s(camera.height)
    n = len(snapshot.rso_r)
    los = LinesOfSight(snapshot, t_mid, np.arange(n))
    mags = snapshot.rso_magnitudes()
    lit = np.isfinite(mags)
    paths = sample_sources(camera, profile, shutter, los.take(np.flatnonzero(lit)), radius, substep_px,
                           max_off_axis_rad, True)
    keep = np.flatnonzero(lit)[paths.keep]
    electrons = np.zeros(n)
    electrons[lit] = sensor.electrons(mags[lit], np.full(int(lit.sum()), SUN_B_V))
    flux = electrons[keep] * star_illumination(camera, sensor.optics, *paths.mid)
    add_sources(signal, paths, flux, camera, sensor, radius, shutter)
    marks = np.array([shutter.start_s, t_mid, shutter.start_s + shutter.exposure_s])
    x, y = positions(camera, profile, los, marks, max_off_axis_rad)
    rendered = np.zeros(n, dtype=bool)
    rendered[keep] = True
    ids = np.array([r.ident for r in snapshot.scene.rsos], dtype=np.int64)
    return RSOTruth(ids=ids, x=x[:, 1], y=y[:, 1], x_start=x[:, 0], y_start=y[:, 0], x_end=x[:, 2],
                    y_end=y[:, 2], mag=mags, electrons=electrons, range_km=snapshot.rso_ranges_km(), lit=lit,
                    rendered=rendered)


def _snapshot(orbital: OrbitalScene | Snapshot | None, timing: FrameTiming, t_mid: float) -> Snapshot | None:
    if orbital is None or isinstance(orbital, Snapshot):
        return orbital
    if not isinstance(orbital, OrbitalScene):
        raise InvalidInputError(f"orbital must be an OrbitalScene or a Snapshot, got {type(orbital).__name__}")
    if timing.epoch is None:
        raise InvalidInputError("satellites need an absolute time: give FrameTiming(epoch=Time(...))")
    return orbital.snapshots(timing.time_at(t_mid))[0]


def _reordered(paths: SourcePaths, order: NDArray[np.intp]) -> SourcePaths:
    s = paths.samples
    samples = type(s)(s.x[order], s.y[order], s.t_lo[order], s.t_hi[order])
    pick = [(p[0][order], p[1][order]) for p in (paths.start, paths.mid, paths.end)]
    return SourcePaths(paths.keep[order], samples, *pick)


def _colours(b_v: ArrayLike | None, n: int) -> NDArray[np.float64]:
    if b_v is None:
        return np.full(n, np.nan)
    colours = np.asarray(b_v, dtype=float)
    if colours.shape != (n,):
        raise InvalidInputError(f"b_v must have shape ({n},), got {colours.shape}")
    return colours


def _background(background_e, sky_background: SkyBackground | None, camera: Camera, sensor: Sensor):
    if sky_background is None:
        return background_e
    if not isinstance(sky_background, SkyBackground):
        raise InvalidInputError("sky_background must be a SkyBackground or None")
    return np.asarray(background_e, dtype=float) + sky_background.electrons(camera, sensor)


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


def _frozen(background_e: float | ArrayLike) -> float | NDArray[np.float64]:
    """A scalar as float, an array as a read-only copy (the truth must not change under us)."""
    arr = np.asarray(background_e, dtype=float)
    if arr.ndim == 0:
        return float(arr)
    arr = arr.copy()
    arr.flags.writeable = False
    return arr
