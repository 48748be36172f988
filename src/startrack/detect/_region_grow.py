"""Jacobs 1995's region growing with a jump scan (§2.2.1).

The thesis scans only every ``jump``-th row and column for a light pixel (a star of at least 10
pixels is 3 pixels across, so a jump of 3 cannot miss it), grows a region from each pixel found
with **4-connectivity**, breadth first, erasing the pixels it takes, and keeps growing past the
border of the search area so that no remainder is found again as another star.

The regions it finds are exactly the 4-connected components of the light pixels that contain at
least one pixel of the scan grid (rows and columns ``0, jump, 2 jump, ...`` of the search area),
and that is how they are computed here: one labelling pass and a selection, vectorised, with
the same result as the seed's pixel loop (its erasing only prevents finding a component twice).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._label import Regions, regions_from_index

FOUR_CONNECTED = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=bool)
"""The 4-connectivity structure (``scipy.ndimage.generate_binary_structure(2, 1)``)."""
DEFAULT_JUMP_PX = 3


def grow_regions(mask: NDArray[np.bool_], jump: int = DEFAULT_JUMP_PX) -> Regions:
    """4-connected regions of ``mask`` (H, W) reached from the scan grid of step ``jump`` (>= 1).

    Regions are numbered in the order the seed's scan finds them (row by row of the grid, then
    column); a region touching no grid pixel is not found.
    """
    from scipy import ndimage  # here, not at import: only this grouping uses it (issue 20)

    labels, n = ndimage.label(mask, structure=FOUR_CONNECTED)
    if n == 0:
        return regions_from_index(np.zeros(0, np.int64), np.zeros(0, np.int64),
                                  np.zeros(0, np.int64), 0)
    grid = labels[::jump, ::jump].ravel()
    found, first = np.unique(grid[grid > 0], return_index=True)
    order = found[np.argsort(first, kind="stable")]  # scan order of each region's first hit
    number = np.full(n + 1, -1, dtype=np.int64)
    number[order] = np.arange(order.size)
    flat = np.flatnonzero(labels)
    keep = number[labels.ravel()[flat]] >= 0
    flat = flat[keep]
    y, x = np.divmod(flat, mask.shape[1])
    return regions_from_index(number[labels.ravel()[flat]], y, x, order.size)
