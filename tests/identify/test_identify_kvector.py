"""The k-vector range search against a brute-force scan."""

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.identify import KVector


@pytest.mark.parametrize("dist", ["uniform", "clustered", "ties"])
def test_query_matches_brute_force(dist):
    rng = np.random.default_rng(7)
    if dist == "uniform":
        keys = rng.uniform(0, 1, 5000)
    elif dist == "clustered":
        keys = np.concatenate([rng.normal(0.2, 0.01, 3000), rng.uniform(0, 5, 2000)])
    else:
        keys = np.round(rng.uniform(0, 1, 5000), 2)
    keys = np.sort(keys).astype(np.float32)
    kv = KVector.build(keys)
    lows = rng.uniform(keys[0] - 0.1, keys[-1], 300)
    highs = lows + rng.uniform(0, 0.2, 300)
    starts, stops = kv.query_many(lows, highs)
    for lo, hi, a, b in zip(lows, highs, starts, stops, strict=True):
        lo32, hi32 = np.float32(lo), np.float32(hi)
        expected = np.flatnonzero((keys >= lo32) & (keys <= hi32))
        got = np.arange(a, b)
        assert np.array_equal(got, expected)


def test_empty_and_outside_ranges():
    kv = KVector.build(np.array([1.0, 2.0, 3.0]))
    assert kv.query(5.0, 6.0) == (3, 3)
    assert kv.query(-2.0, -1.0) == (0, 0)
    assert kv.query(2.0, 2.0) == (1, 2)
    assert KVector.build(np.zeros(0)).query(0.0, 1.0) == (0, 0)


def test_unsorted_keys_are_refused():
    with pytest.raises(InvalidInputError, match="sorted"):
        KVector.build(np.array([2.0, 1.0]))


def test_integer_keys_with_bounds_on_the_keys():
    """The pattern database's keys are uint32 with many repeats, and its bounds are integers too."""
    rng = np.random.default_rng(3)
    keys = np.sort(rng.integers(0, 2000, 20_000)).astype(np.uint32)
    kv = KVector.build(keys)
    lows = rng.integers(0, 2100, 500).astype(float)
    highs = lows + rng.integers(0, 30, 500)
    starts, stops = kv.query_many(lows, highs)
    assert np.array_equal(starts, np.searchsorted(keys, lows.astype(np.uint32), side="left"))
    assert np.array_equal(stops, np.searchsorted(keys, highs.astype(np.uint32), side="right"))
