"""The confirmation's cone and pair queries against the plain forms they replace.

:class:`~startrack.identify._verify.SkyBands` (a sort of unit vectors by z) must find the stars a
KD-tree finds in a cone, and the stars :func:`~startrack.identify._refine.stars_in_cone` finds among
the brightest; :func:`~startrack.identify._refine.predicted_pairs` within a radius R, cut to a
smaller radius r, must equal the match made at r; and the level sets of
:func:`~startrack.identify._quad_matcher.level_stars` must hold the database's verification stars.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from startrack.camera import Camera
from startrack.identify._database import DatabaseSettings, PatternDatabase
from startrack.identify._quad_matcher import level_stars
from startrack.identify._refine import match_predicted, predicted_pairs, stars_in_cone
from startrack.identify._verify import SkyBands


def _unit(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


@pytest.mark.parametrize("chord", [0.0, 0.005, 0.02, 0.3, 1.2, 1.9, 2.5])
def test_band_cone_finds_the_kd_tree_stars(chord):
    rng = np.random.default_rng(4)
    vectors = _unit(rng, 20_000)
    vectors[:4] = [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]  # poles, sector ends
    bands, tree = SkyBands(vectors), cKDTree(vectors)
    edges = [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [-1.0, 1e-12, 0.0], [-1.0, -1e-12, 0.0], [0.3, 0.0, 0.954]]
    for axis in [*_unit(rng, 40), *(np.array(e) / np.linalg.norm(e) for e in edges)]:  # poles, longitude +-180
        got = bands.query_ball_point(axis, chord)
        assert np.array_equal(got, np.sort(tree.query_ball_point(axis, chord)))
        assert got.dtype == np.int64


@pytest.mark.parametrize(("radius_deg", "count"), [(3.0, 20_000), (7.0, 500), (40.0, 15_000), (170.0, 20_000)])
def test_brightest_in_cone_equals_the_linear_scan(radius_deg, count):
    """Both the band's pass (a narrow cone over many stars) and the fallback to the first
    ``count`` stars (a wide cone, or few stars) give the linear scan's indices."""
    rng = np.random.default_rng(5)
    vectors = _unit(rng, 20_000)
    neighbour = rng.uniform(0.0, 2e-4, size=len(vectors))
    bands = SkyBands(vectors)
    for axis in _unit(rng, 20):
        expected = stars_in_cone(vectors, count, axis, math.radians(radius_deg), neighbour, 1e-4)
        got = bands.brightest_in_cone(count, axis, math.radians(radius_deg), neighbour, 1e-4)
        assert np.array_equal(got, expected)


def test_sky_bands_rejects_vectors_of_the_wrong_shape():
    with pytest.raises(ValueError, match=r"shape \(S, 3\)"):
        SkyBands(np.zeros((4, 2)))


@pytest.mark.parametrize("k1", [0.0, -0.05])
def test_pairs_within_a_larger_radius_cut_to_a_smaller_one_equal_the_match_there(k1):
    """The greedy closest-first match at r is the match at R > r cut to the pairs within r, in
    the same order; the count of stars in the image is the numpy projection's."""
    rng = np.random.default_rng(6)
    camera = Camera(width=1024, height=768, fx=3000.0, k1=k1)
    for _ in range(20):
        truth = camera.pixel_to_vector(rng.uniform(-50, 1074, 300), rng.uniform(-50, 818, 300))
        x_true, y_true = camera.vector_to_pixel(truth[:40])
        x, y = x_true + rng.normal(0.0, 3.0, 40), y_true + rng.normal(0.0, 3.0, 40)
        img, cat, d2, n_in = predicted_pairs(truth, np.eye(3), camera, x, y, 7.5)
        px, py = camera.vector_to_pixel(truth)
        assert n_in == np.count_nonzero(camera.in_image(px, py))
        for r in (7.5, 3.0, 1.5):
            keep = d2 <= r * r
            want_img, want_cat = match_predicted(truth, np.eye(3), camera, x, y, r)
            assert np.array_equal(img[keep], want_img) and np.array_equal(cat[keep], want_cat)
        assert np.all(np.diff(d2) >= 0.0)


def test_level_stars_hold_the_databases_verification_stars():
    rng = np.random.default_rng(7)
    vectors = _unit(rng, 500)
    levels = rng.integers(0, 8, size=500).astype(np.uint16)
    db = PatternDatabase(settings=DatabaseSettings(), cat_index=np.arange(1000, 1500), hip=np.arange(500),
                         vectors=vectors, mag=np.zeros(500, np.float32), level_fov_rad=np.radians([5.0, 10.0, 20.0]),
                         pattern_stars=np.zeros((0, 4), np.uint16), pattern_ratios=np.zeros((0, 5), np.uint16),
                         pattern_largest=np.zeros(0, np.uint16), level_offsets=np.zeros(4, np.int64),
                         verify_levels=levels)
    for level in range(3):
        stars = level_stars(db, level)
        assert stars is level_stars(db, level)  # kept
        _, want_vectors, want_rows = db.verification_stars(level)
        order = np.argsort(stars.catalog_rows)
        assert np.array_equal(stars.catalog_rows[order], want_rows)
        assert np.array_equal(stars.vectors[order], want_vectors)
        assert np.all(np.diff(stars.vectors[:, 2]) >= 0.0)  # in ascending order of z
