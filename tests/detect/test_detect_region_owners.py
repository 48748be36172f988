"""``detect._fine_pass.owners``: which region holds a pixel, found among the regions' own pixels
rather than in a frame-sized map."""

from __future__ import annotations

import numpy as np

from startrack.detect._fine_pass import owners
from startrack.detect._label import label_regions


def test_owners_agree_with_a_frame_sized_map():
    rng = np.random.default_rng(1)
    mask = rng.random((60, 90)) > 0.8
    regions = label_regions(mask)
    frame = np.full(mask.shape, -1)
    frame[regions.y, regions.x] = regions.index
    y, x = rng.integers(0, 60, 500), rng.integers(0, 90, 500)
    np.testing.assert_array_equal(owners(regions, y, x, 90), frame[y, x])
    assert (owners(regions, y, x, 90) >= 0).any() and (owners(regions, y, x, 90) < 0).any()


def test_no_regions_own_nothing():
    regions = label_regions(np.zeros((5, 5), dtype=bool))
    np.testing.assert_array_equal(owners(regions, np.array([0, 4]), np.array([1, 2]), 5), [-1, -1])
