"""Parameters and helpers of the streaked-frame levels ``streak`` and ``rso`` (Sease 2013).

Sease 2013 states no camera. The defaults are those of
``benchmarks/streak_benchmark.py`` and ``docs/attitude_and_rate.md``: 1024 x 1024 px, 22.8 deg
field (80 arcsec/px, matching the seed's "1/2 px = 40 arcsec"), Gaussian PSF sigma 1 px, sky
20 e- and read noise 5 e- per pixel, stars of 1e5-5e5 e- per exposure
(:mod:`startrack.analysis._streak_scenes`). The module name starts with an underscore, so it is
not taken for a level.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ....camera import Camera
from ....simulate import Snapshot
from ..._streak_scenes import StreakScene, render_streak_scene
from .._params import Param, SpecError
from ._common import CAMERA_PARAMS


def camera_params(**defaults: Any) -> tuple[Param, ...]:
    """The campaign's pinhole-camera parameters (``fov_deg``, ``width``, ``height``) with other defaults."""
    return tuple(dataclasses.replace(p, default=defaults[p.name]) for p in CAMERA_PARAMS)


STREAK_CAMERA_PARAMS = camera_params(fov_deg=22.8, width=1024, height=1024)
"""The pinhole camera, with the Sease 2013 defaults above."""

STREAK_SCENE_PARAMS = (
    Param("psf_sigma_px", "float", 1.0, "Gaussian PSF sigma (px)", lo=0.3, hi=10.0),
    Param("sky_e", "float", 20.0, "flat sky background per pixel over the exposure (e-)", lo=0.0, hi=1e6),
    Param("read_noise_e", "float", 5.0, "read noise per pixel, 1-sigma (e-)", lo=0.0, hi=1e4),
    Param("star_electrons", "floats", (1e5, 5e5), "stars' signal over the exposure, uniform in [lo, hi] (e-)",
          lo=1.0, hi=1e12, length=2),
    Param("margin_px", "float", 15.0, "every star path stays this far inside the image (px)", lo=0.0, hi=1000.0),
    Param("gap_px", "float", 15.0, "least distance between two star paths (px): streaks that cross are "
          "redrawn, as the seed's corrupted-ROI rule would drop them", lo=0.0, hi=1000.0),
)


def streak_camera(params: Mapping[str, Any]) -> Camera:
    """The pinhole camera of a cell."""
    return Camera.from_fov(params["width"], params["height"], fov_deg=params["fov_deg"])


def check_range(params: Mapping[str, Any], name: str) -> None:
    """Refuse a ``floats`` range whose lower end exceeds its upper."""
    lo, hi = params[name]
    if lo > hi:
        raise SpecError(f"{name}: the lower end must not exceed the upper, got [{lo:g}, {hi:g}]")


def render(params: Mapping[str, Any], rot_start: Rotation, omega: NDArray, exposure_s: float, vectors: NDArray,
           flux: NDArray, rng: np.random.Generator, rso: Snapshot | None = None) -> StreakScene:
    """:func:`~startrack.analysis._streak_scenes.render_streak_scene` with the cell's camera and noise."""
    return render_streak_scene(streak_camera(params), rot_start, omega, exposure_s, vectors, flux, rso=rso,
                               psf_sigma_px=params["psf_sigma_px"], background_e=params["sky_e"],
                               read_noise_e=params["read_noise_e"], rng=rng)


def star_flux(params: Mapping[str, Any], count: int, rng: np.random.Generator, scale: float = 1.0) -> NDArray:
    """Electrons of ``count`` stars, uniform in ``star_electrons`` times ``scale``."""
    low, high = params["star_electrons"]
    return rng.uniform(low, high, count) * scale


def truth_pairs(scene: StreakScene, ends_a: NDArray, ends_b: NDArray) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """The true object of each measured streak (nearest midpoint) and whether its group-A end is
    the start of the exposure (nearer the true start than the true end)."""
    mids = 0.5 * (scene.start_xy + scene.end_xy)
    centres = 0.5 * (ends_a + ends_b)
    index = np.array([np.nanargmin(np.linalg.norm(mids - c, axis=1)) for c in centres], dtype=np.intp)
    to_start = np.linalg.norm(ends_a - scene.start_xy[index], axis=1)
    return index, to_start < np.linalg.norm(ends_a - scene.end_xy[index], axis=1)


def in_time_order(scene: StreakScene, ends_a: NDArray, ends_b: NDArray) -> tuple[NDArray[np.intp], NDArray, NDArray]:
    """(true index, start ends (N, 2), end ends (N, 2)) of measured streaks, ordered by the truth."""
    index, a_start = truth_pairs(scene, ends_a, ends_b)
    starts = np.where(a_start[:, None], ends_a, ends_b)
    return index, starts, np.where(a_start[:, None], ends_b, ends_a)
