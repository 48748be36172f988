"""Verification of a candidate attitude and the probability that it is a false match.

A candidate (attitude and focal length) predicts where the database's verification stars fall.
Each of the n brightest image stars either has a predicted star within ``radius_px`` or not.
If the candidate were wrong, a star would find a neighbour by chance with probability
p = m * pi * r^2 / (W * H) for m predicted stars in a W x H image, independently, so k or more
chance matches among n stars have the binomial tail probability P(X >= k; n, p). Over the T
candidates tried, the probability that any wrong one did this well is at most T times that
(Bonferroni). The test is made at two radii fixed in advance, r and r / 2
(:data:`TEST_RADIUS_FRACTIONS`), and the smaller bound, times two, is reported
(:func:`false_match_bound`): chance matches at half the radius are four times less likely, so a
sparse field whose few extra stars sit where predicted is confirmed, while a real lens whose
stars land up to r off keeps the wide test. A match is accepted when that bound is below the
caller's threshold.
This is the reasoning tetra3 uses for its mismatch probability; the test here counts only the
stars that were not used to form the candidate.
"""

from __future__ import annotations

import functools
import math
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation
from scipy.special import bdtrc

from ..camera import Camera
from ..catalog import chord_from_angle
from ..errors import InvalidInputError, as_float_array


@dataclass(frozen=True)
class Projection:
    """Database stars predicted inside the image: indices and pixel positions."""

    star: NDArray[np.int64]
    x: NDArray[np.float64]
    y: NDArray[np.float64]


def project_stars(tree: cKDTree, vectors: NDArray, rot_cam_from_icrs: Rotation, camera: Camera,
                  keep: Callable[[NDArray], NDArray] | None = None) -> Projection:
    """Stars (of a KD-tree over their ICRS unit vectors) that land in the image.

    Parameters
    ----------
    tree : scipy.spatial.cKDTree
        Built on ``vectors``.
    vectors : ndarray, shape (S, 3)
        ICRS unit vectors.
    keep : callable, optional
        Given the indices of the stars in the field, returns a mask of those to keep.
    """
    matrix = rot_cam_from_icrs.as_matrix()
    idx = field_cone(tree, matrix, camera, keep)
    if idx.size == 0:
        return Projection(idx, np.zeros(0), np.zeros(0))
    x, y = camera.vector_to_pixel(vectors[idx] @ matrix.T)
    inside = camera.in_image(x, y)
    return Projection(idx[inside], x[inside], y[inside])


class SkyBands:
    """Unit vectors (S, 3) indexed for cone queries: in :data:`SKY_SECTORS` sectors of longitude,
    each sorted by z (one sort, about a tenth of the cost of building a KD-tree over them). A
    query reads, in each sector the cone can reach, the band of z within its reach, and tests
    each vector there in one compiled pass (:func:`.match_kernel.band_cone`).

    :meth:`query_ball_point` returns the indices (ascending) of the vectors within a chord of a
    unit vector, the same set as ``cKDTree.query_ball_point`` (up to rounding at the chord)."""

    def __init__(self, vectors: NDArray[np.float64]):
        vectors = as_float_array(vectors, "vectors")
        if vectors.ndim != 2 or vectors.shape[1] != 3:
            raise InvalidInputError(f"vectors must have shape (S, 3), got {vectors.shape}")
        self.vectors = np.ascontiguousarray(vectors)
        lon = np.arctan2(vectors[:, 1], vectors[:, 0])
        sector = np.minimum((np.floor((lon + math.pi) / (2.0 * math.pi) * SKY_SECTORS)).astype(np.int64),
                            SKY_SECTORS - 1)
        self.order = np.lexsort((vectors[:, 2], sector))
        self.sector_starts = np.searchsorted(sector[self.order], np.arange(SKY_SECTORS + 1))
        self.sorted_vectors = np.take(vectors, self.order, axis=0)
        self.z_sorted = np.ascontiguousarray(self.sorted_vectors[:, 2])
        self._neighbours: tuple = (None, None)

    def query_ball_point(self, axis: NDArray, chord: float) -> NDArray[np.int64]:
        """Indices (ascending) of the vectors within ``chord`` (straight-line distance) of the
        unit vector ``axis`` (3,)."""
        return _kernel().band_cone(self.sorted_vectors, self.order, self.z_sorted, self.sector_starts,
                                   np.ascontiguousarray(axis, dtype=np.float64), float(chord))

    def brightest_in_cone(self, count: int, axis: NDArray, radius_rad: float, neighbour_rad: NDArray,
                          min_neighbour_rad: float) -> NDArray[np.int64]:
        """The indices (ascending) that :func:`.refine.stars_in_cone` finds on the unsorted
        vectors: those among the first ``count`` within ``radius_rad`` of the unit vector ``axis``
        (3,) whose ``neighbour_rad`` (S,) is at least ``min_neighbour_rad``, the same test on the
        same numbers, reading the sectors and bands of z the cone reaches
        (:func:`.match_kernel.band_cone_stars`)."""
        if self._neighbours[0] is not neighbour_rad:  # the values in the vectors' order of z, kept for the next call
            self._neighbours = (neighbour_rad, np.take(neighbour_rad, self.order))
        return _kernel().band_cone_stars(self.vectors, self.sorted_vectors, self.order, self.z_sorted,
                                         self.sector_starts, int(count),
                                         np.ascontiguousarray(axis, dtype=np.float64),
                                         math.cos(min(radius_rad, math.pi)), neighbour_rad, self._neighbours[1],
                                         float(min_neighbour_rad))


SKY_SECTORS = 32
"""Sectors of longitude of a :class:`SkyBands` (11.25 deg each: a cone of 10 deg radius away from
the poles reads 3 of them)."""

_BANDS: dict[int, SkyBands] = {}
"""The :class:`SkyBands` of :func:`bands_of`, by ``id`` of their owner (an entry goes with its owner)."""


def bands_of(owner: object, vectors: NDArray[np.float64]) -> SkyBands:
    """A :class:`SkyBands` over ``vectors`` (S, 3), made on the first call for ``owner`` (an object
    that holds them, such as a :class:`.field_stars.FieldStars`: one sort, a few ms for 100,000
    stars) and kept while the owner lives."""
    bands = _BANDS.get(id(owner))
    if bands is None:
        bands = _BANDS[id(owner)] = SkyBands(vectors)
        weakref.finalize(owner, _BANDS.pop, id(owner), None)
    return bands


@functools.cache
def _kernel() -> ModuleType:
    """:mod:`._match_kernel` (numba is imported on first use)."""
    from . import _match_kernel as match_kernel

    return match_kernel


def field_cone(tree: cKDTree | SkyBands, matrix_cam_from_icrs: NDArray, camera: Camera,
               keep: Callable[[NDArray], NDArray] | None = None) -> NDArray[np.int64]:
    """Indices (into the vectors a KD-tree or :class:`SkyBands` was built on) of the stars within
    1.05 times the half diagonal of the image (at most 1.5 rad) of the boresight of an attitude
    matrix (3, 3, camera from ICRS), filtered by ``keep`` as in :func:`project_stars`: every star
    that can land in the image, and none behind it."""
    half_diag = math.radians(camera.fov_diagonal_deg) / 2.0 * 1.05
    axis = matrix_cam_from_icrs[2]  # the last row is the boresight in ICRS
    idx = np.asarray(tree.query_ball_point(axis, chord_from_angle(min(half_diag, 1.5), "half_diag")), dtype=np.int64)
    if keep is not None and idx.size:
        idx = idx[keep(idx)]
    return idx


def match_nearest(img_x: NDArray, img_y: NDArray, cat_x: NDArray, cat_y: NDArray,
                  radius_px: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs (image index, catalog index), each star used once, closest pairs first, within the radius.

    Only pairs within the radius are ever formed (KD-trees), so memory stays proportional to
    the stars, however many there are.
    """
    empty = np.zeros(0, dtype=np.int64)
    if img_x.size == 0 or cat_x.size == 0:
        return empty, empty
    return closest_pairs_first(*_pairs_within(img_x, img_y, cat_x, cat_y, radius_px))


def closest_pairs_first(i: NDArray, c: NDArray, d2: NDArray) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """From candidate pairs (image index i, catalog index c, squared distance d2; (P,) each), keep
    the closest pairs first, each star used once (greedy). Returns the kept (i, c), closest first."""
    order = np.argsort(d2, kind="stable")
    i, c = i[order].astype(np.int64), c[order].astype(np.int64)
    if i.size == 0 or (np.bincount(i).max() == 1 and np.bincount(c).max() == 1):  # no star in two pairs
        return i, c
    taken_i, taken_c, keep = set(), set(), []
    for k, (ik, ck) in enumerate(zip(i.tolist(), c.tolist(), strict=True)):
        if ik not in taken_i and ck not in taken_c:  # plain Python: numpy scalar indexing costs more here
            taken_i.add(ik)
            taken_c.add(ck)
            keep.append(k)
    return i[keep], c[keep]


DENSE_PAIRS_LIMIT = 200_000
"""Above this many (image, catalog) pairs, candidate pairs come from KD-trees, not a full table."""


def _pairs_within(img_x, img_y, cat_x, cat_y, radius_px: float):
    """(image index, catalog index, squared distance) of every pair closer than the radius."""
    if img_x.size * cat_x.size <= DENSE_PAIRS_LIMIT:
        d2 = (img_x[:, None] - cat_x[None, :]) ** 2 + (img_y[:, None] - cat_y[None, :]) ** 2
        i, c = np.nonzero(d2 <= radius_px * radius_px)
        return i, c, d2[i, c]
    img_tree = cKDTree(np.column_stack([img_x, img_y]))
    cat_tree = cKDTree(np.column_stack([cat_x, cat_y]))
    pairs = img_tree.sparse_distance_matrix(cat_tree, radius_px, output_type="ndarray")
    return pairs["i"], pairs["j"], pairs["v"] ** 2


def false_match_probability(n_matched: int, n_tested: int, n_predicted: int, radius_px: float,
                            width: int, height: int, n_trials: int) -> float:
    """Bound on the probability that a wrong candidate matched this many stars by chance.

    Parameters
    ----------
    n_matched : int
        Image stars (beyond those that formed the candidate) with a predicted star nearby.
    n_tested : int
        Image stars tested (beyond those that formed the candidate).
    n_predicted : int
        Catalog stars predicted inside the image.
    radius_px : float
        Match radius in pixels.
    width, height : int
        Image size in pixels.
    n_trials : int
        Candidates tried so far (the Bonferroni factor).

    Returns
    -------
    float
        ``min(1, n_trials * P(X >= n_matched))`` with X ~ Binomial(n_tested, p).
    """
    if n_tested <= 0 or n_matched <= 0:
        return 1.0
    p = min(1.0, n_predicted * math.pi * radius_px**2 / (width * height))
    tail = float(bdtrc(n_matched - 1, n_tested, p))
    return min(1.0, max(1, n_trials) * tail)


TEST_RADIUS_FRACTIONS = (1.0, 0.5)
"""Radii of the false-match test as fractions of the match radius; the bound pays a Bonferroni
factor of their number."""


def false_match_bound(extra_d2_px2: NDArray, n_tested: int, n_predicted: int, radius_px: float,
                      width: int, height: int, n_trials: int) -> float:
    """The false-match bound of :func:`false_match_probability`, tested at every radius of
    :data:`TEST_RADIUS_FRACTIONS` and corrected for testing that many (module docstring).

    Parameters
    ----------
    extra_d2_px2 : ndarray, shape (K,)
        Squared distances (pixels^2) of the matched image stars beyond those that formed the
        candidate to their predicted stars, all within ``radius_px``.
    n_tested, n_predicted, radius_px, width, height, n_trials
        As for :func:`false_match_probability`.

    Returns
    -------
    float
        ``min(1, len(TEST_RADIUS_FRACTIONS) * min over radii of the bound at that radius)``.
    """
    d2 = np.asarray(extra_d2_px2, dtype=float)
    counts = [int(np.count_nonzero(d2 <= (f * radius_px) ** 2)) for f in TEST_RADIUS_FRACTIONS]
    return false_match_bound_counts(counts, n_tested, n_predicted, radius_px, width, height, n_trials)


def false_match_bound_counts(n_matched: Sequence[int], n_tested: int, n_predicted: int, radius_px: float,
                             width: int, height: int, n_trials: int) -> float:
    """:func:`false_match_bound` from the number of matched image stars (beyond those that formed the
    candidate) within each radius of :data:`TEST_RADIUS_FRACTIONS` (times ``radius_px``), in that
    order: the form for matches made at each radius (a closest-first greedy match at a smaller
    radius keeps exactly the pairs of the match at the larger one that lie within it)."""
    best = min(false_match_probability(int(k), n_tested, n_predicted, f * radius_px, width, height, n_trials)
               for k, f in zip(n_matched, TEST_RADIUS_FRACTIONS, strict=True))
    return min(1.0, len(TEST_RADIUS_FRACTIONS) * best)
