"""Cone search: the stars within an angular radius of a direction.

Angles become chords on the unit sphere (``2 sin(theta / 2)``), so a cone is a ball in 3-D and a
k-d tree answers it exactly. A star exactly on the cone's edge may fall either side (rounding).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from ..errors import InvalidInputError
from ..frames import normalize
from .star_catalog import StarCatalog

if TYPE_CHECKING:
    from astropy.time import Time


def chord_from_angle(theta_rad: float, name: str, allow_zero: bool = False) -> float:
    """Chord length ``2 sin(theta / 2)`` of an angle in (0, pi] ([0, pi] with ``allow_zero``).

    Raises InvalidInputError naming the parameter ``name`` for any other angle.
    """
    theta = float(theta_rad)
    low_ok = theta >= 0.0 if allow_zero else theta > 0.0
    if not (low_ok and theta <= np.pi):
        interval = "[0, pi]" if allow_zero else "(0, pi]"
        raise InvalidInputError(f"{name} must be in {interval} radians, got {theta_rad!r}")
    return 2.0 * np.sin(theta / 2.0)


def _radius_chord(radius_rad: float) -> float:
    return chord_from_angle(radius_rad, "radius_rad", allow_zero=True)


def _unit_vectors(vectors: ArrayLike, name: str, shape: str) -> NDArray[np.float64]:
    v = np.asarray(vectors, dtype=float)
    norms = np.linalg.norm(v, axis=-1) if v.ndim and v.shape[-1] == 3 else None
    if norms is None or not np.all(np.isfinite(norms)) or np.any(norms == 0):
        raise InvalidInputError(f"{name} must be finite non-zero vectors of shape {shape}, "
                                f"got shape {v.shape}")
    return normalize(v)


class ConeIndex:
    """A k-d tree over unit vectors (N, 3) for repeated cone searches.

    Parameters
    ----------
    vectors : (N, 3) ICRS directions (normalised here), e.g. ``catalog.vectors(epoch)``.
    """

    def __init__(self, vectors: ArrayLike) -> None:
        v = _unit_vectors(vectors, "vectors", "(N, 3)")
        if v.ndim != 2:
            raise InvalidInputError(f"vectors must have shape (N, 3), got {v.shape}")
        self.vectors = v
        self._tree = cKDTree(v)

    def __len__(self) -> int:
        return len(self.vectors)

    def query(self, center: ArrayLike, radius_rad: float) -> NDArray[np.int64]:
        """Sorted indices of the vectors within ``radius_rad`` of ``center`` (3,)."""
        c = _unit_vectors(center, "center", "(3,)")
        if c.shape != (3,):
            raise InvalidInputError(f"center must have shape (3,), got {c.shape}")
        found = self._tree.query_ball_point(c, _radius_chord(radius_rad), return_sorted=True)
        return np.asarray(found, dtype=np.int64)

    def query_many(self, centers: ArrayLike, radius_rad: float) -> list[NDArray[np.int64]]:
        """For each of ``centers`` (M, 3), the sorted indices within ``radius_rad`` of it."""
        c = _unit_vectors(centers, "centers", "(M, 3)")
        if c.ndim != 2:
            raise InvalidInputError(f"centers must have shape (M, 3), got {c.shape}")
        found = self._tree.query_ball_point(c, _radius_chord(radius_rad), return_sorted=True)
        return [np.asarray(f, dtype=np.int64) for f in found]


def cone_search(catalog: StarCatalog, center_vec: ArrayLike, radius_rad: float,
                epoch_jyear: float | Time | None = None) -> NDArray[np.int64]:
    """Sorted indices of the catalog stars within ``radius_rad`` of ``center_vec`` (3,) (ICRS).

    Positions are at ``epoch_jyear`` (Julian year TDB or ``Time``; None: the catalog epoch). A
    single query is a vectorised chord test over all N stars (no tree to build); use
    :class:`ConeIndex` for many queries on the same stars.
    """
    c = _unit_vectors(center_vec, "center_vec", "(3,)")
    if c.shape != (3,):
        raise InvalidInputError(f"center_vec must have shape (3,), got {c.shape}")
    chord = _radius_chord(radius_rad)
    d2 = np.sum((catalog.vectors(epoch_jyear) - c) ** 2, axis=-1)
    return np.flatnonzero(d2 <= chord * chord).astype(np.int64)
