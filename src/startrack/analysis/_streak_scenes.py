"""Streaked and smeared frames with known truth, for the Sease 2013 and Samaan 2002 campaigns.

A thin set-up around :func:`startrack.simulate.render_stars` (its sub-step streaks, noise chain
and truth; ``docs/simulation.md``): stars are placed where their whole path stays in the image
(:func:`star_field`, and apart from each other with :func:`separated_field`), given the
electrons asked for through the sensor's zero point, and rendered at a constant camera-frame
rate. An RSO comes from a :class:`startrack.simulate.Snapshot` taken at mid-exposure: a real
orbital scene (:mod:`startrack.analysis._rso_passes`, Sease 2013 Table 4.3) or
:func:`turning_rso_snapshot`, a satellite 200 km from the observer whose line of sight turns
across the sky at a chosen angular rate. Noise: Poisson shot noise on signal + a flat sky,
Gaussian read noise, no quantisation (float images), no bias, no full well.

The camera turns at ``omega`` (camera frame, rad/s): a star at camera vector ``v0`` at the start
of the exposure is at ``exp(-[omega x] t) v0`` at time t (:mod:`startrack.rate`'s convention).
These scenes were first written for the rate tests (``tests/rate/streak_scenes.py``) and
``benchmarks/streak_benchmark.py``; the campaign levels ``streak``, ``rso`` and ``smear`` use
them from here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError, require
from ..simulate import (
    RSO,
    Detector,
    NoiseModel,
    Optics,
    Orbit,
    OrbitalScene,
    Sensor,
    Snapshot,
    Truth,
    magnitude_from_electrons,
    render_stars,
)

EPOCH = Time("2026-03-20T12:00:00", scale="utc")
"""Epoch of :func:`turning_rso_snapshot`'s geometry (only the Sun's side matters: the RSO is lit)."""
OBSERVER_R_KM = np.array([7000.0, 0.0, 0.0])
OBSERVER_V_KM_S = np.array([0.0, 7.5, 0.0])
SUN_KM = np.array([1.496e8, 0.0, 0.0])
RSO_RANGE_KM = 200.0
APERTURE_AREA_M2 = 1e-3
"""Aperture of the sensor: only the zero point of the electrons <-> magnitude conversion."""


@dataclass(frozen=True)
class StreakScene:
    """A rendered frame and its truth (N objects: the stars in the order given, then any RSO).

    Attributes
    ----------
    image : ndarray, shape (H, W)
        Electrons (float, no quantisation).
    rot_start, rot_end : Rotation
        ``rot_cam_from_icrs`` at the start and the end of the exposure.
    omega_rad_s : ndarray, shape (3,)
        The camera's rate (camera frame).
    start_xy, end_xy : ndarray, shape (N, 2)
        Pixel positions at the start and the end of the exposure (simulator truth; NaN for an
        object the simulator did not draw).
    icrs : ndarray, shape (N, 3)
        Reference directions (the stars'; an RSO's at the start of the exposure).
    is_rso : ndarray of bool, shape (N,)
    truth : startrack.simulate.Truth
        The simulator's own truth of the frame (what ``campaign rerun --save-image`` writes).
    """

    image: NDArray[np.float64]
    camera: Camera
    rot_start: Rotation
    rot_end: Rotation
    omega_rad_s: NDArray[np.float64]
    exposure_s: float
    start_xy: NDArray[np.float64]
    end_xy: NDArray[np.float64]
    icrs: NDArray[np.float64]
    is_rso: NDArray[np.bool_]
    truth: Truth


def streak_sensor(exposure_s: float, psf_sigma_px: float = 1.0, read_noise_e: float = 5.0) -> Sensor:
    """The sensor of these scenes: a Gaussian PSF, read noise, no full well (nothing saturates)."""
    detector = Detector(read_noise_e=read_noise_e, full_well_e=1e12)
    return Sensor(Optics(aperture_area_m2=APERTURE_AREA_M2, psf_sigma_px=psf_sigma_px), detector,
                  exposure_s=exposure_s)


def turning_rso_snapshot(rot_start: Rotation, vector_cam0: ArrayLike, own_cam: ArrayLike, exposure_s: float,
                         mag: float) -> Snapshot:
    """One lit satellite seen along ``vector_cam0`` (camera frame) at the start of the exposure,
    its sight line turning at ``own_cam`` (rad/s, camera axes at the start), 200 km away.

    The snapshot is at mid-exposure (the renderer's t = 0), with a fixed V magnitude ``mag``.
    """
    own = rot_start.inv().apply(np.asarray(own_cam, dtype=float))
    los_mid = Rotation.from_rotvec(own * exposure_s / 2).apply(rot_start.inv().apply(np.asarray(vector_cam0)))
    r = OBSERVER_R_KM + RSO_RANGE_KM * los_mid
    v = OBSERVER_V_KM_S + RSO_RANGE_KM * np.cross(own, los_mid)
    scene = OrbitalScene(Orbit(EPOCH, OBSERVER_R_KM, OBSERVER_V_KM_S), (RSO(Orbit(EPOCH, r, v), 90001, mag),))
    return Snapshot(EPOCH, OBSERVER_R_KM, OBSERVER_V_KM_S, r[None], v[None], SUN_KM, -SUN_KM / 400, scene)


def render_streak_scene(
    camera: Camera,
    rot_start: Rotation,
    omega_rad_s: ArrayLike,
    exposure_s: float,
    vectors_cam0: ArrayLike,
    flux_e: ArrayLike,
    *,
    rso: Snapshot | None = None,
    psf_sigma_px: float = 1.0,
    background_e: float = 20.0,
    read_noise_e: float = 5.0,
    rng: np.random.Generator | int | None = None,
) -> StreakScene:
    """Simulate stars (camera vectors (N, 3) at the start, electrons ``flux_e`` (N,)) for ``exposure_s``.

    Parameters
    ----------
    camera : Camera
    rot_start : Rotation
        ``rot_cam_from_icrs`` at the start of the exposure.
    omega_rad_s : array_like, shape (3,)
        The camera's constant rate (camera frame, rad/s).
    exposure_s : float
    vectors_cam0 : array_like, shape (N, 3)
        The stars' camera-frame directions at the start of the exposure.
    flux_e : array_like, shape (N,)
        Their signal electrons over the exposure.
    rso : Snapshot, optional
        Satellites at mid-exposure (the first one is the scene's RSO, appended after the stars).
    psf_sigma_px, background_e, read_noise_e : float
        Gaussian PSF sigma (px), flat sky (electrons per pixel per exposure), read noise (e-).
    rng : numpy.random.Generator, int or None

    Returns
    -------
    StreakScene
    """
    omega = np.asarray(omega_rad_s, dtype=float)
    vectors = np.asarray(vectors_cam0, dtype=float)
    flux = np.asarray(flux_e, dtype=float)
    if vectors.ndim != 2 or vectors.shape[1] != 3 or flux.shape != (len(vectors),):
        raise InvalidInputError(f"vectors_cam0 must be (N, 3) and flux_e (N,), got {vectors.shape}, {flux.shape}")
    sensor = streak_sensor(exposure_s, psf_sigma_px, read_noise_e)
    rot_mid = Rotation.from_rotvec(-omega * exposure_s / 2) * rot_start
    icrs = rot_start.inv().apply(vectors)
    sim = render_stars(camera, rot_mid, icrs, magnitude_from_electrons(flux, sensor), np.arange(len(vectors)),
                       sensor=sensor, background_e=background_e, rng=rng, rate_rad_s=omega, orbital=rso,
                       noise=NoiseModel(quantize=False, saturate=False, bias=False))
    t = sim.truth
    count = len(vectors) + (rso is not None)
    start, end = np.full((count, 2), np.nan), np.full((count, 2), np.nan)
    start[t.ids] = np.stack([t.x_start, t.y_start], axis=1)
    end[t.ids] = np.stack([t.x_end, t.y_end], axis=1)
    is_rso = np.zeros(count, dtype=bool)
    if rso is not None:
        rsos = require(t.rsos, "the simulated truth's RSO tracks")
        start[-1] = [rsos.x_start[0], rsos.y_start[0]]
        end[-1] = [rsos.x_end[0], rsos.y_end[0]]
        is_rso[-1] = True
        icrs = np.vstack([icrs, rso.lines_of_sight(np.array([[-exposure_s / 2]]), np.array([0]))[0]])
    return StreakScene(np.asarray(sim.image, dtype=float), camera, t.rot_start, t.rot_end, omega, exposure_s,
                       start, end, icrs, is_rso, t)


def star_field(camera: Camera, omega_rad_s: ArrayLike, exposure_s: float, count: int,
               rng: np.random.Generator | int | None, margin_px: float = 12.0) -> NDArray[np.float64]:
    """Camera vectors (count, 3) at the start of stars whose whole path stays ``margin_px`` inside
    the image (uniform over the pixels that qualify)."""
    rng = np.random.default_rng(rng)
    omega = np.asarray(omega_rad_s, dtype=float)
    chosen: list[NDArray] = []
    for _ in range(1000):
        if len(chosen) >= count:
            return np.array(chosen[:count])
        x = rng.uniform(0, camera.width - 1, 4 * count)
        y = rng.uniform(0, camera.height - 1, 4 * count)
        v0 = camera.pixel_to_vector(x, y)
        inside = np.ones(len(x), dtype=bool)
        for t in np.linspace(0, exposure_s, 9):
            px, py = camera.vector_to_pixel(Rotation.from_rotvec(-omega * t).apply(v0))
            inside &= camera.in_image(px, py, margin_px)
        chosen.extend(v0[inside])
    raise InvalidInputError("no star path stays inside the image: the streaks are longer than the field")


def star_paths(camera: Camera, omega_rad_s: ArrayLike, exposure_s: float, vectors_cam0: ArrayLike,
               samples: int = 30) -> NDArray[np.float64]:
    """Pixel positions (N, samples, 2) of stars along their paths over the exposure."""
    omega = np.asarray(omega_rad_s, dtype=float)
    vectors = np.asarray(vectors_cam0, dtype=float)
    steps = [np.stack(camera.vector_to_pixel(Rotation.from_rotvec(-omega * t).apply(vectors)), axis=1)
             for t in np.linspace(0.0, exposure_s, samples)]
    return np.stack(steps, axis=1)


def rso_path(camera: Camera, rot_start: Rotation, omega_rad_s: ArrayLike, exposure_s: float, snapshot: Snapshot,
             samples: int = 30) -> NDArray[np.float64]:
    """Pixel positions (samples, 2) of a snapshot's first satellite over the exposure, the
    snapshot taken at mid-exposure (light time included; NaN behind the camera)."""
    t = np.linspace(0.0, exposure_s, samples)
    los = snapshot.lines_of_sight((t - exposure_s / 2)[None], np.array([0]))[0]
    rots = Rotation.from_rotvec(-np.outer(t, np.asarray(omega_rad_s, dtype=float))) * rot_start
    x, y = camera.vector_to_pixel(rots.apply(los))
    return np.stack([x, y], axis=1)


def path_gap_px(paths_a: NDArray, paths_b: NDArray) -> float:
    """Least distance (px) between any sampled point of paths (N, S, 2) and of paths (M, S, 2)."""
    a, b = paths_a.reshape(-1, 2), paths_b.reshape(-1, 2)
    if not len(a) or not len(b):
        return float("inf")
    return float(np.min(np.linalg.norm(a[:, None] - b[None], axis=2)))


def paths_apart(paths: NDArray, gap_px: float) -> bool:
    """Whether every two paths (N, S, 2) stay at least ``gap_px`` apart."""
    return all(path_gap_px(paths[i:i + 1], paths[:i]) >= gap_px for i in range(1, len(paths)))


def separated_field(camera: Camera, omega_rad_s: ArrayLike, exposure_s: float, count: int,
                    rng: np.random.Generator, *, margin_px: float = 15.0, gap_px: float = 15.0,
                    avoid_xy: NDArray | None = None, avoid_px: float = 0.0, tries: int = 200) -> NDArray[np.float64]:
    """:func:`star_field` redrawn until every two star paths stay ``gap_px`` apart (streaks that
    cross would be rejected as corrupted ROIs) and, with ``avoid_xy`` (S, 2) (another object's
    sampled path), every star path stays ``avoid_px`` from it.

    Raises
    ------
    InvalidInputError
        When ``tries`` fields all fail (too many stars or too long streaks for the image).
    """
    for _ in range(tries):
        vectors = star_field(camera, omega_rad_s, exposure_s, count, rng, margin_px)
        paths = star_paths(camera, omega_rad_s, exposure_s, vectors)
        if paths_apart(paths, gap_px) and (avoid_xy is None or path_gap_px(paths, avoid_xy[None]) >= avoid_px):
            return vectors
    raise InvalidInputError(f"no field of {count} star paths {gap_px:g} px apart in {tries} draws; "
                            "ask for fewer stars or shorter streaks")


def spin_rate(theta_rad: float, rate_rad_s: float, azimuth_rad: float = 0.0) -> NDArray[np.float64]:
    """Camera-frame rate of magnitude ``rate_rad_s`` whose axis is ``theta`` from the boresight (+z)."""
    axis = np.array([np.sin(theta_rad) * np.cos(azimuth_rad), np.sin(theta_rad) * np.sin(azimuth_rad),
                     np.cos(theta_rad)])
    return rate_rad_s * axis
