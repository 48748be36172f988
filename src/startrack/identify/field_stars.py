"""Every catalog star to a magnitude limit, indexed for the final match of an identified image.

The pattern database keeps only the stars its levels use, so a faint neighbour of a database
star may be missing from it; the last re-match of a solve therefore looks at the whole catalog
to the database's magnitude limit, so that each image star gets its nearest catalog star.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..catalog import load_catalog


@dataclass(frozen=True)
class FieldStars:
    """Catalog rows (S,), brightest first, their ICRS unit vectors (S, 3) at ``epoch_jyear`` and a
    KD-tree on them (so that sorted tree queries return the brightest stars first)."""

    rows: NDArray[np.int64]
    vectors: NDArray[np.float64]
    tree: cKDTree
    epoch_jyear: float


@lru_cache(maxsize=4)
def field_stars(max_mag: float, epoch_jyear: float) -> FieldStars:
    """Catalog stars with V <= ``max_mag``, brightest first (built once per process and limit)."""
    catalog = load_catalog()
    rows = np.flatnonzero(np.isfinite(catalog.v_mag) & (catalog.v_mag <= max_mag))
    rows = rows[np.argsort(catalog.v_mag[rows], kind="stable")]
    vectors = catalog.take(rows).vectors(epoch_jyear)
    return FieldStars(rows, vectors, cKDTree(vectors), epoch_jyear)
