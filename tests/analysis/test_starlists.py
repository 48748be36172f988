"""The benchmark star-list generator (benchmarks/starlists.py): seeded, true to its truth."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from startrack.analysis import _starlists as starlists
from startrack.catalog import load_catalog
from startrack.units import PIXEL

BASE = starlists.Conditions(fov_deg=15.0, max_stars=1000)


@pytest.fixture(scope="module")
def sky():
    return starlists.load_sky(BASE, load_catalog())


def _lists(sky, n=20, seed=3, **changes):
    return starlists.generate_star_lists(replace(BASE, **changes), n, seed, sky=sky)


def test_same_seed_same_lists_and_list_i_independent_of_count(sky):
    a, b, c = _lists(sky, 6), _lists(sky, 6), _lists(sky, 3)
    for s, t in zip(a, b, strict=True):
        np.testing.assert_array_equal(s.x, t.x)
        np.testing.assert_array_equal(s.flux, t.flux)
        np.testing.assert_array_equal(s.hip, t.hip)
        np.testing.assert_array_equal(s.rot_cam_from_icrs.as_quat(), t.rot_cam_from_icrs.as_quat())
    for s, t in zip(a[:3], c, strict=True):
        np.testing.assert_array_equal(s.y, t.y)
    other = _lists(sky, 6, seed=4)
    assert not np.allclose(a[0].rot_cam_from_icrs.as_quat(), other[0].rot_cam_from_icrs.as_quat())


def test_real_entries_project_within_the_centroid_noise(sky):
    cat = load_catalog()
    row = {int(h): i for i, h in enumerate(cat.hip)}
    vectors = cat.vectors(BASE.epoch_jyear)
    camera = BASE.camera
    normalised = []
    for s in _lists(sky, 30):
        real = s.is_real
        v = vectors[[row[int(h)] for h in s.hip[real]]]
        px, py = camera.vector_to_pixel(s.rot_cam_from_icrs.apply(v))
        np.testing.assert_allclose(px, s.true_x[real], atol=1e-6 * PIXEL)
        np.testing.assert_allclose(py, s.true_y[real], atol=1e-6 * PIXEL)
        assert 0.1 <= s.sigma_px <= 0.5
        normalised.append(np.concatenate([s.x[real] - px, s.y[real] - py]) / s.sigma_px)
    normalised = np.concatenate(normalised)
    assert np.max(np.abs(normalised)) < 5.5
    assert 0.9 < np.std(normalised) < 1.1
    assert abs(np.mean(normalised)) < 0.1


def test_false_star_count_as_requested(sky):
    for s in _lists(sky, 10, false_stars_range=(4, 4)):
        assert np.count_nonzero(~s.is_real) == 4 == s.n_false
        assert np.all(s.hip[~s.is_real] == -1)
        assert np.all(np.isnan(s.true_x[~s.is_real]))
        assert np.all(BASE.camera.in_image(s.x, s.y))
    assert all(s.is_real.all() for s in _lists(sky, 10, false_stars_range=(0, 0)))


def test_missing_fraction_removes_that_share_of_real_stars(sky):
    full = _lists(sky, 10, missing_fraction_range=(0.0, 0.0), false_stars_range=(0, 0))
    half = _lists(sky, 10, missing_fraction_range=(0.5, 0.5), false_stars_range=(0, 0))
    for f, h in zip(full, half, strict=True):
        assert len(h) == len(f) - round(0.5 * len(f))
        assert set(h.hip) <= set(f.hip)


def test_brightest_first_truncated_and_realistic_star_counts(sky):
    lists = starlists.generate_star_lists(starlists.Conditions(fov_deg=15.0), 200, 5, sky=sky)
    counts = np.array([len(s) for s in lists])
    assert counts.max() <= 40
    assert 15 <= np.median(counts) <= 35
    assert all(np.all(np.diff(s.flux) <= 0) for s in lists)
