"""The catalog triangle directory of Cole & Crassidis (Huffman 2006 §5.4.2),
built from a star-pair directory.

Every triple of directory stars whose three pairs are all in the pair directory (all sides
shorter than the field's diagonal), with its area and polar moment (planar or spherical, see
:mod:`._triangle_features`), sorted by area with a k-vector over the areas: a range query on the
area returns the candidate triangles of an image triangle, which are then filtered by moment.
The directory is large (about 1.5 million triangles for a 15 deg field, 35 MB), which is the
method's known cost (§1.20); it is built on demand into the user cache (DESIGN.md, Data) and
kept in memory per process.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import NDArray

from .. import cache
from ._kvector import KVector
from ._pair_database import PairDatabase, PairSettings
from ._pair_search import expand_ranges
from ._triangle_features import SUBDIVISION_LEVELS, check_variant, triangle_features

TRIANGLES_KIND = "triangles"
TRIANGLES_VERSION = 1
BUILD_CHUNK = 10_000
"""Triangles whose features are computed at once (bounds the memory of the spherical subdivision)."""


@dataclass(frozen=True)
class TriangleDatabase:
    """A loaded triangle directory.

    Attributes
    ----------
    variant : {"planar", "spherical"}
    triangles : ndarray of int32, shape (T, 3)
        Indices into the pair directory's stars (ascending within a row), sorted by area.
    area : ndarray, shape (T,)
        Areas, ascending (planar: chord triangle, unit-sphere units; spherical: steradians).
    moment : ndarray, shape (T,)
        Polar moments about the centroid.
    """

    settings: PairSettings
    variant: str
    triangles: NDArray[np.int32]
    area: NDArray[np.float64]
    moment: NDArray[np.float64]
    kvector: KVector = field(repr=False)

    def between(self, low: float, high: float) -> slice:
        """The slice of triangles whose area lies in [low, high]."""
        start, stop = self.kvector.query(low, high)
        return slice(start, stop)


def directory_triangles(pairs: NDArray) -> NDArray[np.int32]:
    """Every triple (T, 3), ascending within a row, whose three pairs are all in ``pairs`` (P, 2)."""
    edges = np.sort(pairs.astype(np.int64), axis=1)
    edges = edges[np.lexsort((edges[:, 1], edges[:, 0]))]
    base = int(edges.max()) + 1
    keys = edges[:, 0] * base + edges[:, 1]
    block_end = np.searchsorted(edges[:, 0], edges[:, 0], "right")
    owner, other = expand_ranges(np.arange(1, len(edges) + 1), block_end)  # later edges of the same first star
    tri = np.column_stack([edges[owner, 0], edges[owner, 1], edges[other, 1]])
    closing = tri[:, 1] * base + tri[:, 2]
    found = np.searchsorted(keys, closing)
    exists = keys[np.minimum(found, len(keys) - 1)] == closing
    return tri[exists].astype(np.int32)


def _build(pdb: PairDatabase, variant: str) -> dict[str, NDArray]:
    tri = directory_triangles(pdb.pairs)
    area, moment = np.empty(len(tri)), np.empty(len(tri))
    for start in range(0, len(tri), BUILD_CHUNK):
        part = slice(start, start + BUILD_CHUNK)
        area[part], moment[part] = triangle_features(pdb.vectors[tri[part]], variant)
    order = np.argsort(area, kind="stable")
    return {"triangles": tri[order], "area": area[order], "moment": moment[order]}


_LOADED: dict[tuple[PairSettings, str], TriangleDatabase] = {}


def load_triangle_database(pdb: PairDatabase, variant: str = "planar") -> TriangleDatabase:
    """The triangle directory of a pair directory's stars, built into the cache on first use."""
    key = (pdb.settings, check_variant(variant))
    if key not in _LOADED:
        params = {**asdict(pdb.settings), "variant": variant, "levels": SUBDIVISION_LEVELS}
        arrays = cache.load_or_build(TRIANGLES_KIND, TRIANGLES_VERSION, params, lambda: _build(pdb, variant))
        _LOADED[key] = TriangleDatabase(pdb.settings, variant, arrays["triangles"], arrays["area"], arrays["moment"],
                                        KVector.build(arrays["area"]))
    return _LOADED[key]
