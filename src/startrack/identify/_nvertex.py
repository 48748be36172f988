"""Lost-in-space identification by the n-vertex match (Huffman 2006 §5.5.4 pp.111-113, Figs. 5.12-5.13,
Table 5.4), n = 3, 4 or 5, for a camera whose focal length is known
(to a few percent at most).

A modified Pyramid that matches all n stars of a set at once:

1. Sets of n of the brightest image stars in the generalised Pyramid order
   (:func:`.star_order.ordered_star_sets`).
2. The **C matrix**: one column per baseline (vertex pair u < v, numbered AB, AC, AD, ..., BC, BD,
   ...), holding every catalog pair whose angle fits that baseline (k-vector range query on the
   angle; the seed keys on sin^2 of the angle, which is monotonic and gives the same pairs).
3. The **S matrix**: for a pair (p, q) in column j, ``q in S[p, j]`` and ``p in S[q, j]``; a cell
   holds a *set* (a star can be in several pairs of one baseline). Stored per column as the sorted
   keys ``p * base + q`` of its pairs both ways round (:class:`SMatrix`).
4. The **self-consistency check**: catalog stars X with B* in S[X, AB], C* in S[X, AC], ... (the
   vertices joined on A's column), such that every other baseline is in S too: S[B*, BC] holds C*,
   S[B*, BD] holds D*, S[C*, CD] holds D*, ... (:func:`consistent_ngons`). The handedness of A, B, C
   must be the image's (a mirror image is refused here).
5. When several n-gons pass, a further star is added (the seed's "5th star", matching all n + 1
   stars) until one is left (:func:`.pair_search.pivot`); its rotation (q-method on all its stars)
   is confirmed with :mod:`._confirm`. The search stops at the first n-gon that is confirmed.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..camera import Camera
from ..errors import InvalidInputError
from ._candidate import MatchOutcome
from ._pair_database import PairDatabase
from ._pair_search import (
    PairSearchOptions,
    PatternMatcher,
    SearchContext,
    extend_by_angle,
    handedness,
    join_rows,
    search,
)

N_VERTICES = (3, 4, 5)


@dataclass(frozen=True)
class NVertexOptions(PairSearchOptions):
    """Settings of the n-vertex matcher (see :class:`.pair_search.PairSearchOptions`)."""

    max_pivots: int = 3


def baselines(n: int) -> list[tuple[int, int]]:
    """Vertex pairs of an n-gon in the seed's column order: AB, AC, ..., BC, BD, ... (0-based)."""
    return list(itertools.combinations(range(n), 2))


class SMatrix:
    """The S matrix of a C matrix: which catalog stars are paired with which in each baseline column.

    Columns are prepared on first use, so a check that fails early never sorts the others.

    Parameters
    ----------
    c_matrix : list of ndarray, each (K_j, 2)
        Catalog pairs of each baseline column (either way round).
    """

    def __init__(self, c_matrix: list[NDArray]):
        self.c_matrix = [np.asarray(c, dtype=np.int64).reshape(-1, 2) for c in c_matrix]
        self.base = int(max((c.max() for c in self.c_matrix if c.size), default=0)) + 1
        self._oriented: dict[int, NDArray[np.int64]] = {}
        self._keys: dict[int, NDArray[np.int64]] = {}

    def oriented(self, column: int) -> NDArray[np.int64]:
        """The column's pairs both ways round (2K, 2): (p, q) for every q in S[p, column]."""
        if column not in self._oriented:
            c = self.c_matrix[column]
            self._oriented[column] = np.concatenate([c, c[:, ::-1]])
        return self._oriented[column]

    def contains(self, p: NDArray, q: NDArray, column: int) -> NDArray[np.bool_]:
        """Element-wise: is star q in cell S[p, column]?"""
        if column not in self._keys:
            pairs = self.oriented(column)
            self._keys[column] = np.sort(pairs[:, 0] * self.base + pairs[:, 1])
        keys = self._keys[column]
        if keys.size == 0:
            return np.zeros(np.shape(p), dtype=bool)
        wanted = np.asarray(p, dtype=np.int64) * self.base + np.asarray(q, dtype=np.int64)
        return keys[np.minimum(np.searchsorted(keys, wanted), keys.size - 1)] == wanted

    def row(self, p: int) -> list[set[int]]:
        """Row p of S: for each column, the set of stars paired with star p (as in Table 5.4)."""
        return [set(c[c[:, 0] == p, 1].tolist()) for c in map(self.oriented, range(len(self.c_matrix)))]


def consistent_ngons(c_matrix: list[NDArray], n: int) -> NDArray[np.int64]:
    """Catalog stars (T, n) for vertices A, B, ... that pass the self-consistency check.

    Parameters
    ----------
    c_matrix : list of ndarray, each (K_j, 2)
        Catalog pairs of each baseline, in the order of :func:`baselines`.
    n : int
        Vertices.
    """
    columns = {pair: j for j, pair in enumerate(baselines(n))}
    s = SMatrix(c_matrix)
    table = s.oriented(columns[0, 1])  # X = A and B* in S[X, AB]
    for v in range(2, n):
        if len(table) == 0:
            break
        table = join_rows(table, [0], s.oriented(columns[0, v]))  # the v-th vertex in S[X, Av]
        for u in range(1, v):
            table = table[s.contains(table[:, u], table[:, v], columns[u, v])]
    return table.reshape(-1, n) if len(table) else np.zeros((0, n), dtype=np.int64)


def c_matrix_of(ctx: SearchContext, img: tuple[int, ...]) -> list[NDArray]:
    """The C matrix of an image n-gon: the directory pairs fitting each baseline."""
    return [ctx.pairs_fitting(img[u], img[v], both_ways=False) for u, v in baselines(len(img))]


def ngon_candidates(ctx: SearchContext, img: tuple[int, ...]) -> NDArray[np.int64]:
    """Catalog n-gons (T, n) matching image stars ``img`` with the image's handedness."""
    table = consistent_ngons(c_matrix_of(ctx, img), len(img))
    img_hand = handedness(ctx.vec[list(img[:3])])
    return table[handedness(ctx.pdb.vectors[table[:, :3]]) == img_hand]


def match_nvertex(x: NDArray, y: NDArray, camera: Camera, pdb: PairDatabase, *, focal_tolerance: float = 0.0,
                  options: NVertexOptions | None = None, n: int = 4) -> MatchOutcome:
    """Identify image stars with a known camera by the n-vertex match.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Star positions (our pixel convention), brightest first.
    camera : Camera
        The camera (its focal length is taken as known to ``focal_tolerance``).
    pdb : PairDatabase
        A directory for (at least) this camera's diagonal field of view.
    focal_tolerance : float
        Relative uncertainty of the focal length; widens the angle tolerance and lets the
        confirmation refit the focal length.
    options : NVertexOptions, optional
    n : {3, 4, 5}
        Stars matched at once.

    Returns
    -------
    MatchOutcome
        ``Status.OK`` with the confirmed candidate; ``TOO_FEW_STARS`` below max(4, n) stars;
        ``NO_MATCH`` or ``TIMEOUT`` otherwise (mirrored or false star lists end there).
    """
    if n not in N_VERTICES:
        raise InvalidInputError(f"n must be one of {N_VERTICES} vertices, got {n}")
    matcher = PatternMatcher(f"{n}-vertex matcher", n, ngon_candidates, extend_by_angle)
    return search(matcher, x, y, camera, pdb, focal_tolerance, options or NVertexOptions())
