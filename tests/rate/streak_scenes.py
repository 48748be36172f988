"""Streaked star frames with known truth, for the rate tests: :mod:`startrack.analysis._streak_scenes`
re-exported (one implementation of the scenes, which the campaign levels use too).

The only addition is the rate tests' way of asking for an RSO in :func:`render_streak_scene`:
``rso_omega_cam`` (N, 3), whose last row, when non-zero, is that object's own angular velocity
across the sky (camera axes at the start of the exposure, rad/s); it becomes
:func:`startrack.analysis._streak_scenes.turning_rso_snapshot` with that object's electrons.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from startrack.analysis import _streak_scenes as _scenes
from startrack.analysis._streak_scenes import (  # noqa: F401  (re-exported for the tests)
    EPOCH,
    RSO_RANGE_KM,
    StreakScene,
    paths_apart,
    spin_rate,
    star_field,
    star_paths,
    streak_sensor,
    turning_rso_snapshot,
)
from startrack.simulate import magnitude_from_electrons


def render_streak_scene(camera, rot_start, omega_rad_s: ArrayLike, exposure_s: float, vectors_cam0: ArrayLike,
                        flux_e: ArrayLike, *, rso_omega_cam: ArrayLike | None = None, psf_sigma_px: float = 1.0,
                        background_e: float = 20.0, read_noise_e: float = 5.0, rng=None) -> StreakScene:
    """:func:`startrack.analysis._streak_scenes.render_streak_scene`, the last object an RSO when
    its row of ``rso_omega_cam`` (N, 3; rad/s) is non-zero (module docstring)."""
    vectors = np.asarray(vectors_cam0, dtype=float)
    flux = np.asarray(flux_e, dtype=float)
    own = np.zeros((len(vectors), 3)) if rso_omega_cam is None else np.asarray(rso_omega_cam, dtype=float)
    moving = np.linalg.norm(own, axis=1) > 0
    if np.any(moving[:-1]):
        raise ValueError("only the last object may be an RSO")
    kwargs = {"psf_sigma_px": psf_sigma_px, "background_e": background_e, "read_noise_e": read_noise_e, "rng": rng}
    if not moving.size or not moving[-1]:
        return _scenes.render_streak_scene(camera, rot_start, omega_rad_s, exposure_s, vectors, flux, **kwargs)
    mag = float(magnitude_from_electrons(flux[-1:], streak_sensor(exposure_s, psf_sigma_px, read_noise_e))[0])
    rso = turning_rso_snapshot(rot_start, vectors[-1], own[-1], exposure_s, mag)
    return _scenes.render_streak_scene(camera, rot_start, omega_rad_s, exposure_s, vectors[:-1], flux[:-1], rso=rso,
                                       **kwargs)
