"""The pattern database: what it holds, its index, its cache."""

import numpy as np
import pytest

from startrack import cache
from startrack.errors import InvalidInputError
from startrack.identify._database import (
    KEY_BINS,
    LARGEST_LN_STEP,
    LEVEL_SHIFT,
    RATIO_SCALE,
    DatabaseSettings,
    build_database_arrays,
    database_report,
    largest_from_stored,
    largest_to_stored,
    pattern_key,
)
from startrack.identify._patterns import edge_ratios, pair_angles
from startrack.identify._registry import database_settings_for

SMALL = DatabaseSettings(fov_min_deg=20.0, fov_max_deg=30.0, max_mag=7.0)


@pytest.fixture(scope="module")
def arrays():
    return build_database_arrays(SMALL)


def test_levels_cover_the_range(arrays):
    fovs = np.degrees(arrays["level_fov_rad"])
    assert fovs[0] == pytest.approx(20.0) and fovs[-1] >= 30.0
    assert np.all(np.diff(arrays["level_offsets"]) > 0)


def test_stored_ratios_and_edges_match_the_star_vectors(arrays):
    stars = arrays["pattern_stars"]
    ratios, largest = edge_ratios(pair_angles(arrays["vectors"][stars]))
    np.testing.assert_allclose(arrays["pattern_ratios"] / RATIO_SCALE, ratios, atol=1.0 / RATIO_SCALE)
    np.testing.assert_allclose(largest_from_stored(arrays["pattern_largest"]), largest, rtol=LARGEST_LN_STEP)


def test_patterns_fit_their_level_and_are_sorted_by_key(arrays):
    offsets = arrays["level_offsets"]
    for k, fov in enumerate(arrays["level_fov_rad"]):
        sl = slice(offsets[k], offsets[k + 1])
        assert np.all(largest_from_stored(arrays["pattern_largest"][sl]) <= 2 * SMALL.region_fraction * fov * 1.0002)
        keys = pattern_key(arrays["pattern_ratios"][sl])
        assert np.all(np.diff(keys) >= 0)


def test_the_stored_key_index_is_each_level_s_pattern_key_and_its_cells(arrays):
    """Stored since layout 4 (it was recomputed at each load); the same arrays as that recomputation."""
    offsets, keys, starts = arrays["level_offsets"], arrays["keys"], arrays["cell_starts"]
    assert keys.dtype == np.int64 and starts.dtype == np.int64
    assert starts.shape == ((len(offsets) - 1) * KEY_BINS**2 + 1,) and starts[-1] == keys.size
    assert np.all(np.diff(keys) >= 0) and np.all(np.diff(starts) >= 0)
    for k in range(len(offsets) - 1):
        sl = slice(offsets[k], offsets[k + 1])
        np.testing.assert_array_equal(keys[sl], (k << LEVEL_SHIFT) + pattern_key(arrays["pattern_ratios"][sl]))
    cell = np.searchsorted(starts, np.arange(keys.size), side="right") - 1  # the cell each row is in
    in_level = keys & ((1 << LEVEL_SHIFT) - 1)
    np.testing.assert_array_equal(cell, (keys >> LEVEL_SHIFT) * KEY_BINS**2 + in_level // 65536)


def test_patterns_are_unique_within_a_level_and_use_bright_stars(arrays):
    offsets = arrays["level_offsets"]
    for k in range(len(offsets) - 1):
        stars = np.sort(arrays["pattern_stars"][offsets[k]:offsets[k + 1]], axis=1)
        assert len(np.unique(stars, axis=0)) == len(stars)
    assert np.all(arrays["mag"] <= SMALL.max_mag)


def test_report_builds_into_the_cache_and_loads(tmp_path, monkeypatch):
    monkeypatch.setenv(cache.ENV_VAR, str(tmp_path))
    report = database_report(SMALL)
    assert report["n_patterns"] > 1000 and report["file_bytes"] > 0 and report["build_s"] > 0
    again = database_report(SMALL)
    assert np.isnan(again["build_s"])  # reused, not rebuilt


def test_corrupt_database_file_is_rebuilt(tmp_path, monkeypatch):
    from dataclasses import asdict

    from startrack.identify._database import DB_KIND, DB_VERSION, database_path

    monkeypatch.setenv(cache.ENV_VAR, str(tmp_path))
    path = database_path(SMALL)
    path.write_bytes(b"not a database")
    assert cache.load(DB_KIND, DB_VERSION, asdict(SMALL)) is None
    assert database_report(SMALL)["build_s"] > 0


def test_is_cached_is_false_for_a_file_that_would_be_rebuilt(tmp_path, monkeypatch):
    from startrack.identify._database import database_path, is_cached

    monkeypatch.setenv(cache.ENV_VAR, str(tmp_path))
    assert not is_cached(SMALL)
    database_path(SMALL).write_bytes(b"not a database")
    assert not is_cached(SMALL)  # present but damaged: a rebuild would happen, so announce it
    database_report(SMALL)
    assert is_cached(SMALL)


def test_bad_settings_are_refused():
    with pytest.raises(InvalidInputError, match="FOV range"):
        DatabaseSettings(fov_min_deg=30.0, fov_max_deg=10.0)


def test_largest_edges_keep_their_relative_precision_from_arcseconds_to_120_deg():
    """The log scale: 2e-4 relative from a 0.01 deg edge of a 1 deg field to a 120 deg edge of a
    wide one (the old linear scale stopped at 28.6 deg)."""
    angles = np.radians(np.array([0.01, 0.2, 5.0, 37.0, 90.0, 120.0]))
    back = largest_from_stored(largest_to_stored(angles))
    assert np.all(np.abs(back / angles - 1.0) <= LARGEST_LN_STEP)


@pytest.mark.parametrize(("request_deg", "expected"), [
    ((3.0, 100.0), (3.0, 100.0)), ((5.0, 100.0), (3.0, 100.0)), ((10.0, 20.0), (3.0, 100.0)),
    ((1.0, 2.0), (0.97, 2.06)), ((0.5, 100.0), (0.485, 103.0)),
])
def test_every_valid_range_gets_a_database(request_deg, expected):
    """A request inside the default range uses the default database; one reaching outside gets
    a database for just its range, 3 % wider. (5, 100) used to raise 'database FOV range must
    satisfy ... got 4.85 to 103.0' from that margin.)"""
    settings = database_settings_for(request_deg)
    assert (settings.fov_min_deg, settings.fov_max_deg) == pytest.approx(expected)


def test_the_star_tree_is_built_on_first_use_over_the_database_stars(arrays):
    from startrack.identify._database import _from_arrays

    db = _from_arrays(SMALL, arrays)
    assert not db._star_tree  # a load builds no tree
    dist, index = db.tree.query(arrays["vectors"][[0, 5, 9]])
    np.testing.assert_array_equal(index, [0, 5, 9])
    assert np.all(dist == 0.0) and db.tree is db.tree
