"""A strong barrel lens folds back before its corners: what realdata_benchmark --lens-term measures
there (issue 17: its 90 deg, k1 = -0.1 star lists were counted false, solved or not)."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from realdata_benchmark import error_points, error_px, fold_tan, lens_list  # noqa: E402

from startrack import Camera  # noqa: E402
from startrack.frames import random_rotations  # noqa: E402
from startrack.units import PIXEL  # noqa: E402

FOLDING = Camera.from_fov(1600, 1200, 90.0).with_distortion(k1=-0.1)


def test_the_fold_is_where_the_radial_map_stops_growing():
    r = fold_tan(FOLDING)
    assert r == pytest.approx(1.0 / math.sqrt(0.3), rel=1e-9)  # d(r + k1 r^3)/dr = 0
    assert math.degrees(math.atan(r)) == pytest.approx(61.29, abs=0.01)
    assert fold_tan(FOLDING.with_distortion(k1=0.1)) == math.inf
    assert fold_tan(FOLDING.with_distortion(k1=-0.05, k2=0.01)) == math.inf  # k2 keeps it growing


def test_the_error_is_measured_where_the_true_lens_maps_one_to_one():
    corners_x, corners_y = np.array([0.0, 1599.0]), np.array([0.0, 1199.0])
    assert np.isnan(FOLDING.pixel_to_vector(corners_x, corners_y)).all()  # the corners map to no direction
    x, y = error_points(FOLDING)
    assert np.isfinite(FOLDING.pixel_to_vector(x, y)).all()
    truth = random_rotations(1, rng=np.random.default_rng(3))[0]
    assert error_px(truth, SimpleNamespace(rot_cam_from_icrs=truth), FOLDING) < 1e-6 * PIXEL
    x, y = error_points(FOLDING.with_distortion(k1=-0.05))  # folds beyond its corners: the corners themselves
    assert (x[1:].min(), x[1:].max(), y[1:].min(), y[1:].max()) == (0.0, 1599.0, 0.0, 1199.0)


def test_star_lists_hold_no_folded_back_stars():
    rng = np.random.default_rng(5)
    v = rng.normal(size=(3000, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    truth = random_rotations(1, rng=rng)[0]
    cam = truth.apply(v)
    kept = FOLDING.in_image(*FOLDING.vector_to_pixel(cam), margin_px=1.0) & (cam[:, 2] > 0.2)
    folded = kept & (np.hypot(cam[:, 0], cam[:, 1]) >= fold_tan(FOLDING) * cam[:, 2])
    assert folded.sum() > 50  # the polynomial puts them in the frame ...
    mag = np.where(folded, 1.0, 6.0) + rng.uniform(0, 0.5, len(v))  # ... and they are the brightest
    x, y = lens_list(FOLDING, truth, rng, v, mag)
    px, py = FOLDING.vector_to_pixel(cam[folded])
    listed = np.concatenate([x[:10], x[14:]]), np.concatenate([y[:10], y[14:]])  # less the 4 false stars
    d = np.hypot(listed[0][:, None] - px[None], listed[1][:, None] - py[None]).min(axis=1)
    assert np.all(d > 1.5 * PIXEL)  # none of them is listed (0.3 px noise)
