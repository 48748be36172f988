"""Synthetic calibration frames: Hipparcos stars through a known camera, with centroid noise."""

from __future__ import annotations

import functools

import numpy as np
from scipy.spatial.transform import Rotation

from startrack.calibrate._stars import CalibrationFrame
from startrack.catalog import load_catalog
from startrack.frames import random_rotations
from startrack.simulate._scene import project_stars
from startrack.units import DEG


@functools.lru_cache(maxsize=4)
def star_vectors(max_mag: float) -> np.ndarray:
    return load_catalog().brighter_than(max_mag).vectors(2000.0)


def make_frames(camera, n_frames: int, *, rng: int, sigma_px: float = 0.1, max_mag: float = 6.0,
                attitude_error_deg: float = 0.05, outliers: int = 0):
    """Frames with true star positions + Gaussian noise, starting attitudes off by a random
    rotation; ``outliers`` stars per frame get a wrong position (10 to 30 px away).
    Returns the frames and the true attitudes."""
    gen = np.random.default_rng(rng)
    vectors = star_vectors(max_mag)
    frames, truths = [], []
    for rot in random_rotations(n_frames, rng=gen):
        x, y, visible = project_stars(camera, rot, vectors)
        k = int(np.count_nonzero(visible))
        x, y = x[visible] + gen.normal(0, sigma_px, k), y[visible] + gen.normal(0, sigma_px, k)
        if outliers:
            bad = gen.choice(k, outliers, replace=False)
            angle = gen.uniform(0, 2 * np.pi, outliers)
            dist = gen.uniform(10, 30, outliers)
            x[bad] += dist * np.cos(angle)
            y[bad] += dist * np.sin(angle)
        start = Rotation.from_rotvec(gen.normal(0, attitude_error_deg * DEG, 3)) * rot
        frames.append(CalibrationFrame(x, y, vectors[visible], start))
        truths.append(rot)
    return frames, truths
