"""Streaked star images with known truth, for the rate tests and the streak benchmark.

A small stand-in for the simulator's motion blur until it lands: each star (and optional RSO) is
a Gaussian PSF integrated along its path during the exposure (seed 001 §2 "Streaking Dynamics",
notes seed-001-004 §1.8, with samples at mid-step times so the flux is not double-counted at
the ends), then Poisson shot noise, a flat sky background and Gaussian read noise (electrons).

The camera turns at a constant camera-frame rate omega, so a star at camera vector v0 at the
start of the exposure is at ``exp(-[omega x] t) v0`` at time t; an RSO also moves across the sky
at its own (inertial) angular velocity.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from startrack.camera import Camera
from startrack.simulate import render_gaussian_psf

STEP_PX = 0.2


@dataclass(frozen=True)
class StreakScene:
    """A rendered frame and its truth (N objects: the stars, then any RSOs)."""

    image: np.ndarray
    camera: Camera
    rot_start: Rotation  # rot_cam_from_icrs at the start of the exposure
    rot_end: Rotation
    omega_rad_s: np.ndarray
    exposure_s: float
    start_xy: np.ndarray  # (N, 2) pixel positions at the start
    end_xy: np.ndarray
    icrs: np.ndarray  # (N, 3) reference directions (stars; an RSO's at the start)
    is_rso: np.ndarray  # (N,) bool

    @property
    def start_vectors(self) -> np.ndarray:
        return self.camera.pixel_to_vector(self.start_xy[:, 0], self.start_xy[:, 1])

    @property
    def end_vectors(self) -> np.ndarray:
        return self.camera.pixel_to_vector(self.end_xy[:, 0], self.end_xy[:, 1])


def _paths(camera, vectors_cam0, omega, exposure_s, rso_omega_cam):
    """Pixel paths (N, K, 2) at K mid-step times, and the exact start and end positions."""
    ends = _project(camera, vectors_cam0, omega, rso_omega_cam, np.array([0.0, exposure_s]))
    length = np.max(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=-1))
    steps = max(int(np.ceil(length * 1.7 / STEP_PX)), 1)  # arcs are longer than their chords
    mid = (np.arange(steps) + 0.5) / steps * exposure_s
    return _project(camera, vectors_cam0, omega, rso_omega_cam, mid), ends[:, 0], ends[:, 1]


def _project(camera, vectors_cam0, omega, rso_omega_cam, times):
    """Pixel positions (N, T, 2) of the objects at the given times."""
    out = []
    for t in times:
        own = Rotation.from_rotvec(rso_omega_cam * t)  # RSO's own motion (identity for stars)
        turn = Rotation.from_rotvec(-omega * t)
        v = turn.apply(own.apply(vectors_cam0))
        x, y = camera.vector_to_pixel(v)
        out.append(np.stack([x, y], axis=-1))
    return np.stack(out, axis=1)


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
    """Render N objects (camera vectors at the start) turning with the camera for ``exposure_s``.

    ``rso_omega_cam`` (N, 3), rad/s, is each object's own angular velocity across the sky (zero
    for stars), in camera axes at the start.
    """
    rng = np.random.default_rng(rng)
    omega = np.asarray(omega_rad_s, dtype=float)
    n = len(vectors_cam0)
    own = np.zeros((n, 3)) if rso_omega_cam is None else np.asarray(rso_omega_cam, dtype=float)
    path, start, end = _paths(camera, vectors_cam0, omega, exposure_s, own)
    k = path.shape[1]
    image = render_gaussian_psf((camera.height, camera.width), path[..., 0].ravel(), path[..., 1].ravel(),
                                np.repeat(np.asarray(flux_e, dtype=float) / k, k), psf_sigma_px)
    image = rng.poisson(image + background_e).astype(float) + rng.normal(scale=read_noise_e, size=image.shape)
    rot_end = Rotation.from_rotvec(-omega * exposure_s) * rot_start
    return StreakScene(image, camera, rot_start, rot_end, omega, exposure_s, start, end,
                       rot_start.inv().apply(vectors_cam0), np.linalg.norm(own, axis=1) > 0)


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
