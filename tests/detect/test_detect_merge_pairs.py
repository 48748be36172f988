"""The merge's pairwise pre-check (:func:`startrack.detect._merge.apart`) gives the groups the
k-d tree gives: on random point sets with coincident, near-radius and NaN points."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect import _merge
from startrack.detect._merge import MERGE_RADIUS_PX, apart, coincident_groups


def point_sets():
    """Random sets of 0-60 points on a 1000 px frame, some with copies of other points moved
    by up to 1.5 times the merge radius (pairs on both sides of the radius)."""
    rng = np.random.default_rng(17)
    for n in (0, 1, 2, 5, 30, 60):
        for _ in range(20):
            x, y = rng.uniform(0, 1000, n), rng.uniform(0, 1000, n)
            if n > 1 and rng.random() < 0.7:
                k = rng.integers(1, max(2, n // 3))
                pick = rng.choice(n, k, replace=False)
                angle, r = rng.uniform(0, 2 * np.pi, k), rng.uniform(0, 1.5 * MERGE_RADIUS_PX, k)
                x[pick[1:]] = x[pick[:-1]] + (r * np.cos(angle))[1:]
                y[pick[1:]] = y[pick[:-1]] + (r * np.sin(angle))[1:]
            yield x, y, rng.uniform(1, 100, n)


def test_groups_are_the_k_d_trees(monkeypatch):
    sets = list(point_sets())
    fast = [coincident_groups(x, y, f) for x, y, f in sets]
    monkeypatch.setattr(_merge, "MAX_PAIRWISE", -1)  # the k-d tree alone
    slow = [coincident_groups(x, y, f) for x, y, f in sets]
    for (keep, group), (keep_ref, group_ref) in zip(fast, slow, strict=True):
        np.testing.assert_array_equal(keep, keep_ref)
        np.testing.assert_array_equal(group, group_ref)


@pytest.mark.parametrize(("dx", "expected"), [(1.5, True), (1.0, False), (0.0, False), (np.nan, False)])
def test_apart_compares_every_pair(dx, expected):
    x = np.array([0.0, 10.0, 10.0 + dx, 40.0])
    assert apart(x, np.zeros(4), MERGE_RADIUS_PX) is expected
