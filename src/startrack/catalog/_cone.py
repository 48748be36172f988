"""Cone search: the stars within an angular radius of a direction.

Angles become chords on the unit sphere (``2 sin(theta / 2)``, :mod:`startrack.catalog._chord`), so a
cone is a ball in 3-D and a k-d tree answers it exactly. A star exactly on the cone's edge may fall
either side (rounding). :func:`query_cone` is the one cone query over a k-d tree of unit vectors.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from ..errors import InvalidInputError, check_instance
from ..frames import checked_unit_vectors
from ._chord import chord_from_angle
from ._star_catalog import StarCatalog

if TYPE_CHECKING:
    from astropy.time import Time


def _radius_chord(radius_rad: float) -> float:
    return chord_from_angle(radius_rad, "radius_rad", allow_zero=True)


def query_cone(tree: cKDTree, centers: ArrayLike, radius_rad: float, *, return_sorted: bool | None = None,
               workers: int = 1) -> Any:
    """Indices of the points of ``tree`` (unit vectors) within ``radius_rad`` of ``centers``.

    Parameters
    ----------
    tree : cKDTree
        Built on unit vectors (N, 3), e.g. ICRS star directions.
    centers : (3,) or (M, 3) unit vectors, in the tree's frame.
    radius_rad : float
        Cone radius, radians, in [0, pi].
    return_sorted, workers
        As for ``cKDTree.query_ball_point`` (None: a single centre unsorted, several sorted).

    Returns
    -------
    list of int for one centre; an object array (M,) of lists of int for several (typed ``Any``:
    which one depends on the shape of ``centers``).
    """
    return tree.query_ball_point(centers, _radius_chord(radius_rad), return_sorted=return_sorted,
                                 workers=workers)


class ConeIndex:
    """A k-d tree over unit vectors (N, 3) for repeated cone searches.

    Parameters
    ----------
    vectors : (N, 3) ICRS directions (normalised here), e.g. ``catalog.vectors(epoch)``.
    """

    def __init__(self, vectors: ArrayLike) -> None:
        v = checked_unit_vectors(vectors, "vectors", "(N, 3)")
        if v.ndim != 2:
            raise InvalidInputError(f"vectors must have shape (N, 3), got {v.shape}")
        self.vectors = v
        self._tree = cKDTree(v)

    def __len__(self) -> int:
        return len(self.vectors)

    def query(self, center: ArrayLike, radius_rad: float) -> NDArray[np.int64]:
        """Sorted indices of the vectors within ``radius_rad`` of ``center`` (3,)."""
        c = checked_unit_vectors(center, "center", "(3,)")
        if c.shape != (3,):
            raise InvalidInputError(f"center must have shape (3,), got {c.shape}")
        return np.asarray(query_cone(self._tree, c, radius_rad, return_sorted=True), dtype=np.int64)

    def query_many(self, centers: ArrayLike, radius_rad: float) -> list[NDArray[np.int64]]:
        """For each of ``centers`` (M, 3), the sorted indices within ``radius_rad`` of it."""
        c = checked_unit_vectors(centers, "centers", "(M, 3)")
        if c.ndim != 2:
            raise InvalidInputError(f"centers must have shape (M, 3), got {c.shape}")
        return [np.asarray(f, dtype=np.int64) for f in query_cone(self._tree, c, radius_rad, return_sorted=True)]


def cone_search(catalog: StarCatalog, center_vec: ArrayLike, radius_rad: float,
                epoch_jyear: float | Time | None = None) -> NDArray[np.int64]:
    """Sorted indices of the catalog stars within ``radius_rad`` of ``center_vec`` (3,) (ICRS).

    Positions are at ``epoch_jyear`` (Julian year TDB or ``Time``; None: the catalog epoch). A
    single query is a vectorised chord test over all N stars (no tree to build); use
    :class:`ConeIndex` for many queries on the same stars.
    """
    check_instance(catalog, StarCatalog, "catalog")
    c = checked_unit_vectors(center_vec, "center_vec", "(3,)")
    if c.shape != (3,):
        raise InvalidInputError(f"center_vec must have shape (3,), got {c.shape}")
    chord = _radius_chord(radius_rad)
    d2 = np.sum((catalog.vectors(epoch_jyear) - c) ** 2, axis=-1)
    return np.flatnonzero(d2 <= chord * chord).astype(np.int64)
