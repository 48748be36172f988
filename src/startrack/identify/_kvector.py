"""The k-vector range search (Mortari 1997; Huffman 2006 §5.5.4).

Given n sorted keys S, a straight line z(j) = m j + q through the first and last key (widened by a
small margin) and the counts k[j] = #{S <= z(j)} turn the question "which keys lie in [a, b]?"
into two multiplications and two table look-ups, with no search. The answer is a contiguous
slice of the sorted keys, trimmed exactly at both ends.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError


@dataclass(frozen=True)
class KVector:
    """A k-vector over sorted keys.

    Attributes
    ----------
    keys : ndarray, shape (n,)
        The keys, sorted ascending.
    k : ndarray of int, shape (n + 1,)
        ``k[j]`` = number of keys ``<= z(j)``, with ``z(j) = slope * j + intercept``.
    slope, intercept : float
        The line through (0, S[0] - margin) and (n, S[-1] + margin).
    max_bucket : int
        Most keys between two consecutive grid lines (bounds the exact trimming).
    """

    keys: NDArray
    k: NDArray[np.int32] | NDArray[np.int64]
    slope: float
    intercept: float
    max_bucket: int = 0

    @classmethod
    def build(cls, sorted_keys: ArrayLike) -> KVector:
        """Build the index; ``sorted_keys`` must be sorted ascending (checked)."""
        keys = np.asarray(sorted_keys)
        if keys.ndim != 1:
            raise InvalidInputError(f"k-vector keys must be 1-D, got shape {keys.shape}")
        if keys.size and np.any(np.diff(keys) < 0):
            raise InvalidInputError("k-vector keys must be sorted ascending")
        n = keys.size
        if n == 0:
            return cls(keys=keys, k=np.zeros(1, dtype=np.int64), slope=1.0, intercept=0.0, max_bucket=0)
        lo, hi = float(keys[0]), float(keys[-1])
        margin = max(abs(lo), abs(hi), 1.0) * 1e-9
        slope = (hi - lo + 2 * margin) / n
        intercept = lo - margin
        grid = slope * np.arange(n + 1) + intercept
        found = np.searchsorted(keys, grid, side="right")
        k = found.astype(np.int32) if n < 2**31 - 1 else found.astype(np.int64)
        max_bucket = int(np.max(np.diff(k))) if n > 1 else 1
        return cls(keys=keys, k=k, slope=slope, intercept=intercept, max_bucket=max_bucket)

    def query(self, low: float, high: float) -> tuple[int, int]:
        """Half-open index range [start, stop) of the sorted keys in [low, high]."""
        start, stop = self.query_many(np.array([low]), np.array([high]))
        return int(start[0]), int(stop[0])

    def query_many(self, low: ArrayLike, high: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Vectorised :meth:`query` over arrays of bounds; returns (start, stop) arrays.

        The bucket table gives, for each bound, the slice of keys between the two grid lines
        around it; the ends are then trimmed exactly by counting, in one gather of
        ``max_bucket`` keys per bound, the keys of that slice that fall outside the bound.
        """
        low = np.atleast_1d(np.asarray(low, dtype=float))
        high = np.atleast_1d(np.asarray(high, dtype=float))
        n = self.keys.size
        if n == 0:
            zero = np.zeros(low.shape, dtype=np.int64)
            return zero, zero
        start = self._bucket_start(low)
        stop = self._bucket_start(high, upper=True)
        return start, np.maximum(start, stop)

    def _bucket_start(self, bound: NDArray, upper: bool = False) -> NDArray[np.int64]:
        """Index of the first key >= bound (or > bound when ``upper``).

        The line gives the bucket [k[j], k[j + 1]] that holds the answer. Buckets hold one key on
        average, so the short ones (at most :data:`SHORT_BUCKET` keys) are trimmed by one small
        gather; the few long ones (clusters of equal or close keys) by a binary search.
        """
        n = self.keys.size
        j = np.clip(np.floor((bound - self.intercept) / self.slope).astype(np.int64), 0, n - 1)
        first = self.k[j].astype(np.int64)  # keys[:first] <= z(j) <= bound
        width = self.k[j + 1].astype(np.int64) - first
        typed = bound.astype(self.keys.dtype)
        window = np.minimum(first[:, None] + np.arange(SHORT_BUCKET), n - 1)
        values = self.keys[window]
        below = (values <= typed[:, None]) if upper else (values < typed[:, None])
        inside = np.arange(SHORT_BUCKET) < width[:, None]
        result = first + np.count_nonzero(below & inside, axis=1)
        long = np.flatnonzero(width > SHORT_BUCKET)
        if long.size:
            result[long] = np.searchsorted(self.keys, typed[long], side="right" if upper else "left")
        return result


SHORT_BUCKET = 4
"""Buckets of the k-vector up to this many keys are trimmed by a gather, longer ones by a search."""
