"""The pattern database: what it holds, its index, its cache."""

import numpy as np
import pytest

from startrack import cache
from startrack.errors import InvalidInputError
from startrack.identify.database import (
    LARGEST_SCALE_RAD,
    RATIO_SCALE,
    DatabaseSettings,
    build_database_arrays,
    database_report,
    pattern_key,
)
from startrack.identify.patterns import edge_ratios, pair_angles

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
    np.testing.assert_allclose(arrays["pattern_largest"] * LARGEST_SCALE_RAD, largest, atol=LARGEST_SCALE_RAD)


def test_patterns_fit_their_level_and_are_sorted_by_key(arrays):
    offsets = arrays["level_offsets"]
    for k, fov in enumerate(arrays["level_fov_rad"]):
        sl = slice(offsets[k], offsets[k + 1])
        assert np.all(arrays["pattern_largest"][sl] * LARGEST_SCALE_RAD <= 2 * SMALL.region_fraction * fov * 1.0001)
        keys = pattern_key(arrays["pattern_ratios"][sl])
        assert np.all(np.diff(keys) >= 0)


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

    from startrack.identify.database import DB_KIND, DB_VERSION, database_path

    monkeypatch.setenv(cache.ENV_VAR, str(tmp_path))
    path = database_path(SMALL)
    path.write_bytes(b"not a database")
    assert cache.load(DB_KIND, DB_VERSION, asdict(SMALL)) is None
    assert database_report(SMALL)["build_s"] > 0


def test_bad_settings_are_refused():
    with pytest.raises(InvalidInputError, match="FOV range"):
        DatabaseSettings(fov_min_deg=30.0, fov_max_deg=10.0)
