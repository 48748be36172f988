"""Streaked star frames with known truth from the simulator, for the rate tests and benchmark.

Thin set-up around :func:`startrack.simulate.render_stars` (its sub-step streaks, noise chain and
truth; docs/simulation.md): stars are placed where their whole path stays in the image (and, by
the callers, apart), given the electrons asked for through the sensor's zero point, and rendered
at a constant camera-frame rate. An RSO is a satellite of a :class:`startrack.simulate.Snapshot`
200 km from the observer, whose line of sight turns across the sky at a chosen angular rate;
the simulator draws its streak and gives its truth. Noise: Poisson shot noise on signal + a flat
sky, Gaussian read noise, no quantisation (float images), no bias, no full well.

The camera turns at omega (camera frame): a star at camera vector v0 at the start of the
exposure is at ``exp(-[omega x] t) v0`` at time t.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from astropy.time import Time
from scipy.spatial.transform import Rotation

from startrack.camera import Camera
from startrack.simulate import (
    RSO,
    Detector,
    NoiseModel,
    Optics,
    Orbit,
    OrbitalScene,
    Sensor,
    Snapshot,
    magnitude_from_electrons,
    render_stars,
)

EPOCH = Time("2026-03-20T12:00:00", scale="utc")
OBSERVER_R_KM = np.array([7000.0, 0.0, 0.0])  # on the Sun's side of the Earth: the RSO is lit
OBSERVER_V_KM_S = np.array([0.0, 7.5, 0.0])
SUN_KM = np.array([1.496e8, 0.0, 0.0])
RSO_RANGE_KM = 200.0


@dataclass(frozen=True)
class StreakScene:
    """A rendered frame and its truth (N objects: the stars in the order given, then any RSO)."""

    image: np.ndarray
    camera: Camera
    rot_start: Rotation  # rot_cam_from_icrs at the start of the exposure
    rot_end: Rotation
    omega_rad_s: np.ndarray
    exposure_s: float
    start_xy: np.ndarray  # (N, 2) pixel positions at the start (simulator truth)
    end_xy: np.ndarray
    icrs: np.ndarray  # (N, 3) reference directions (stars; an RSO's at the start)
    is_rso: np.ndarray  # (N,) bool


def _sensor(exposure_s: float, psf_sigma_px: float, read_noise_e: float) -> Sensor:
    detector = Detector(read_noise_e=read_noise_e, full_well_e=1e12)
    return Sensor(Optics(aperture_area_m2=1e-3, psf_sigma_px=psf_sigma_px), detector, exposure_s=exposure_s)


def _snapshot(rot_start: Rotation, vector_cam0: np.ndarray, own_cam: np.ndarray, exposure_s: float,
              mag: float) -> Snapshot:
    """One satellite seen along ``vector_cam0`` at the start, its sight line turning at ``own_cam``
    (rad/s, camera axes at the start); the snapshot is at mid-exposure (t = 0)."""
    own = rot_start.inv().apply(own_cam)
    los_mid = Rotation.from_rotvec(own * exposure_s / 2).apply(rot_start.inv().apply(vector_cam0))
    r = OBSERVER_R_KM + RSO_RANGE_KM * los_mid
    v = OBSERVER_V_KM_S + RSO_RANGE_KM * np.cross(own, los_mid)
    scene = OrbitalScene(Orbit(EPOCH, OBSERVER_R_KM, OBSERVER_V_KM_S), (RSO(Orbit(EPOCH, r, v), 90001, mag),))
    return Snapshot(EPOCH, OBSERVER_R_KM, OBSERVER_V_KM_S, r[None], v[None], SUN_KM, -SUN_KM / 400, scene)


def render_streak_scene(
    camera: Camera,
    rot_start: Rotation,
    omega_rad_s,
    exposure_s: float,
    vectors_cam0: np.ndarray,
    flux_e: np.ndarray,
    *,
    rso_omega_cam=None,
    psf_sigma_px: float = 1.0,
    background_e: float = 20.0,
    read_noise_e: float = 5.0,
    rng=None,
) -> StreakScene:
    """Simulate N objects (camera vectors at the start, electrons ``flux_e``) for ``exposure_s``.

    ``rso_omega_cam`` (N, 3), rad/s: at most one row (the last) non-zero, that object's own
    angular velocity across the sky in camera axes at the start; it is rendered as a satellite.
    """
    omega = np.asarray(omega_rad_s, dtype=float)
    vectors = np.asarray(vectors_cam0, dtype=float)
    flux = np.asarray(flux_e, dtype=float)
    own = np.zeros((len(vectors), 3)) if rso_omega_cam is None else np.asarray(rso_omega_cam, dtype=float)
    is_rso = np.linalg.norm(own, axis=1) > 0
    if np.any(is_rso[:-1]):
        raise ValueError("only the last object may be an RSO")
    sensor = _sensor(exposure_s, psf_sigma_px, read_noise_e)
    mags = magnitude_from_electrons(flux, sensor)
    rot_mid = Rotation.from_rotvec(-omega * exposure_s / 2) * rot_start
    stars = ~is_rso
    icrs = rot_start.inv().apply(vectors)
    orbital = _snapshot(rot_start, vectors[-1], own[-1], exposure_s, float(mags[-1])) if is_rso[-1] else None
    sim = render_stars(camera, rot_mid, icrs[stars], mags[stars], np.flatnonzero(stars), sensor=sensor,
                       background_e=background_e, rng=rng, rate_rad_s=omega, orbital=orbital,
                       noise=NoiseModel(quantize=False, saturate=False, bias=False))
    t = sim.truth
    start = np.full((len(vectors), 2), np.nan)
    end = np.full((len(vectors), 2), np.nan)
    start[t.ids] = np.stack([t.x_start, t.y_start], axis=1)
    end[t.ids] = np.stack([t.x_end, t.y_end], axis=1)
    if orbital is not None:
        start[-1] = [t.rsos.x_start[0], t.rsos.y_start[0]]
        end[-1] = [t.rsos.x_end[0], t.rsos.y_end[0]]
    return StreakScene(np.asarray(sim.image, dtype=float), camera, t.rot_start, t.rot_end, omega, exposure_s,
                       start, end, icrs, is_rso)


def star_field(camera: Camera, omega_rad_s, exposure_s: float, count: int, rng, margin_px: float = 12.0):
    """Camera vectors (count, 3) at the start of stars whose whole path stays in the image."""
    rng = np.random.default_rng(rng)
    omega = np.asarray(omega_rad_s, dtype=float)
    chosen = []
    while len(chosen) < count:
        x = rng.uniform(0, camera.width - 1, 4 * count)
        y = rng.uniform(0, camera.height - 1, 4 * count)
        v0 = camera.pixel_to_vector(x, y)
        inside = np.ones(len(x), dtype=bool)
        for t in np.linspace(0, exposure_s, 9):
            px, py = camera.vector_to_pixel(Rotation.from_rotvec(-omega * t).apply(v0))
            inside &= _inside(camera, px, py, margin_px)
        chosen.extend(v0[inside])
    return np.array(chosen[:count])


def _inside(camera, x, y, margin):
    return (x >= margin) & (x <= camera.width - 1 - margin) & (y >= margin) & (y <= camera.height - 1 - margin)


def spin_rate(theta_rad: float, rate_rad_s: float, azimuth_rad: float = 0.0) -> np.ndarray:
    """Camera-frame rate of magnitude ``rate_rad_s`` whose axis is ``theta`` from the boresight (+z)."""
    axis = np.array([np.sin(theta_rad) * np.cos(azimuth_rad), np.sin(theta_rad) * np.sin(azimuth_rad),
                     np.cos(theta_rad)])
    return rate_rad_s * axis
