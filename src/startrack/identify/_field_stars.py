"""Every catalog star to a magnitude limit, indexed for the final match of an identified image.

The pattern database keeps only the stars its levels use, so a faint neighbour of a database
star may be missing from it; the last re-match of a solve therefore looks at the whole catalog
to the database's magnitude limit, so that each image star gets its nearest catalog star.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .. import cache
from ..catalog import angle_from_chord, catalog_identity, chord_from_angle, load_catalog, query_cone


@dataclass(frozen=True)
class FieldStars:
    """Catalog rows (S,), brightest first, their ICRS unit vectors (S, 3) at ``epoch_jyear`` and a
    KD-tree on them (so that sorted tree queries return the brightest stars first)."""

    rows: NDArray[np.int64]
    vectors: NDArray[np.float64]
    tree: cKDTree
    epoch_jyear: float
    index_of_row: NDArray[np.int64]
    """Position in ``rows`` of every catalog row, -1 for rows fainter than the limit."""
    brighter_neighbour_rad: NDArray[np.float64]
    """Angle (S,) from each star to its nearest brighter star, radians; inf when none is closer
    than :data:`NEIGHBOUR_SEARCH_RAD` (so that blends can be found for any focal length)."""

    def vectors_of(self, catalog_rows: NDArray) -> NDArray[np.float64]:
        """ICRS unit vectors (K, 3) of catalog rows at :attr:`epoch_jyear` (any magnitude)."""
        index = self.index_of_row[catalog_rows]
        if np.all(index >= 0):
            return np.take(self.vectors, index, axis=0)  # fancy indexing of (S, 3) costs several times more
        return load_catalog().take(catalog_rows).vectors(self.epoch_jyear)

    def near(self, boresight: NDArray, radius_rad: float) -> NDArray[np.int64]:
        """Indices (into :attr:`rows`) of the stars within ``radius_rad`` of a unit vector."""
        found = query_cone(self.tree, boresight, min(radius_rad, math.pi))
        return np.fromiter(found, dtype=np.int64, count=len(found))

    def around(self, directions: NDArray, radius_rad: float) -> NDArray[np.int64]:
        """Indices (into :attr:`rows`, sorted: brightest first) of the stars within ``radius_rad``
        of any of the unit vectors ``directions`` (N, 3; rows with NaN are skipped).

        Each direction's nearest :data:`AROUND_FIRST_K` stars come from one vectorised tree query;
        only a direction with that many stars in reach (a dense field) is searched again for all.
        """
        directions = directions[np.isfinite(directions).all(axis=1)]  # NaN: a pixel the lens model cannot invert
        chord = chord_from_angle(min(radius_rad, math.pi), "radius_rad", allow_zero=True)
        k = min(AROUND_FIRST_K, len(self.rows))
        dist, index = self.tree.query(directions, k=k, distance_upper_bound=chord)
        dist, index = dist.reshape(len(directions), k), index.reshape(len(directions), k)  # k = 1 gives (N,)
        found = [index[np.isfinite(dist)]]
        for crowded in np.flatnonzero(np.isfinite(dist[:, -1])):
            near = query_cone(self.tree, directions[crowded], min(radius_rad, math.pi))
            found.append(np.asarray(near, dtype=np.int64))
        return np.unique(np.concatenate(found))


AROUND_FIRST_K = 8
"""Stars fetched per direction by :meth:`FieldStars.around` before it falls back to a full search."""

NEIGHBOUR_SEARCH_RAD = np.radians(0.05)
"""Close pairs are looked for out to 0.05 deg: half a pixel of any camera with pixels under 0.1 deg."""


def _brighter_neighbour_rad(tree: cKDTree, vectors: NDArray) -> NDArray[np.float64]:
    """Angle (S,) to the nearest brighter star (stars stored brightest first), inf past the search."""
    pairs = tree.query_pairs(chord_from_angle(NEIGHBOUR_SEARCH_RAD), output_type="ndarray")
    angle = np.full(len(vectors), np.inf)
    if pairs.size:
        chord = np.linalg.norm(vectors[pairs[:, 0]] - vectors[pairs[:, 1]], axis=1)
        np.minimum.at(angle, pairs.max(axis=1), angle_from_chord(chord))
    return angle


FIELD_STARS_KIND = "field-stars"
FIELD_STARS_VERSION = 1
"""Cache kind and version of :func:`field_stars`' arrays (bump the version when they change)."""


@lru_cache(maxsize=4)
def field_stars(max_mag: float, epoch_jyear: float) -> FieldStars:
    """Catalog stars with V <= ``max_mag``, brightest first (built once per process and limit).

    The rows, their vectors at the epoch and the brighter-neighbour angles are kept in the user
    cache (:func:`startrack.cache.load_or_build`), keyed on the limit, the epoch and the catalog
    (:func:`startrack.catalog.catalog_identity`), so that a new process only maps them and builds
    the KD-tree.
    """
    catalog = load_catalog()
    params = {"max_mag": float(max_mag), "epoch_jyear": float(epoch_jyear), "catalog": catalog_identity()}
    arrays = cache.load_or_build(FIELD_STARS_KIND, FIELD_STARS_VERSION, params,
                                 lambda: _field_arrays(max_mag, epoch_jyear))
    rows, vectors = arrays["rows"], arrays["vectors"]
    index_of_row = np.full(len(catalog.hip), -1, dtype=np.int64)
    index_of_row[rows] = np.arange(rows.size)
    tree = cKDTree(vectors, balanced_tree=False)  # exact queries all the same; built in about half the time
    return FieldStars(rows, vectors, tree, epoch_jyear, index_of_row, arrays["brighter_neighbour_rad"])


def _field_arrays(max_mag: float, epoch_jyear: float) -> dict[str, NDArray]:
    """The arrays :func:`field_stars` caches: rows (S,), vectors (S, 3), brighter_neighbour_rad (S,)."""
    catalog = load_catalog()
    rows = np.flatnonzero(np.isfinite(catalog.v_mag) & (catalog.v_mag <= max_mag))
    rows = rows[np.argsort(catalog.v_mag[rows], kind="stable")]
    vectors = catalog.take(rows).vectors(epoch_jyear)
    neighbour = _brighter_neighbour_rad(cKDTree(vectors, balanced_tree=False), vectors)
    return {"rows": rows.astype(np.int64), "vectors": vectors, "brighter_neighbour_rad": neighbour}
