"""Coincident detections merged into one: the detector never reports a star twice.

Two spots can end on the same star: a faint spot (a wing, a noise lump split off by the
deblender, or a fainter neighbour) whose windowed centroid walks to the bright star next to it
converges to the same fixed point, often to the last bit; and the strips of a large frame
(:mod:`._blocks`) can both keep a star that straddles their boundary. The solver refuses two
stars at one position (a pattern with a zero side is degenerate), and a star counted twice
is a false star either way. Every group of detections whose centroids lie within
:data:`MERGE_RADIUS_PX` of each other (single linkage) becomes one detection: the position and
shape of the brightest member, the summed flux and area (they were parts of one spot), the
largest peak.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ._details import DetectionDetails

MERGE_RADIUS_PX = 1.0
"""Detections closer than this (px) are one star: two real stars this close are one spot to any
centroider (their windows converge to the same light centroid)."""

MAX_PAIRWISE = 128
"""Up to this many detections, :func:`apart` compares every pair first (cheaper than a k-d tree)."""

APART_MARGIN = 1.0 + 1e-6
"""Detections farther apart than this times the radius are apart for certain: the k-d tree's
distances (:func:`coincident_groups`) are exact to far better than 1e-6."""


def coincident_groups(x: NDArray, y: NDArray, flux: NDArray,
                      radius_px: float = MERGE_RADIUS_PX) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Groups of detections within ``radius_px`` of each other (single linkage).

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Centroids, px (finite).
    flux : ndarray, shape (N,)
        Brightness; the brightest member represents its group.
    radius_px : float
        Linking distance, px.

    Returns
    -------
    keep : ndarray of int, shape (K,)
        Index of each group's representative, in increasing order (K == N when no two
        detections coincide).
    group : ndarray of int, shape (N,)
        Group number of every detection, 0..K-1 in the order of ``keep``.
    """
    n = len(x)
    if n <= MAX_PAIRWISE and apart(x, y, radius_px * APART_MARGIN):
        return np.arange(n), np.arange(n)
    pairs = cKDTree(np.column_stack([x, y])).query_pairs(radius_px, output_type="ndarray") if n > 1 else \
        np.zeros((0, 2), dtype=np.int64)
    if len(pairs) == 0:
        return np.arange(n), np.arange(n)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    order = np.lexsort((-np.asarray(flux, dtype=float), label))  # by group, brightest first
    first = order[np.r_[True, np.diff(label[order]) != 0]]
    keep = np.sort(first)
    rank = np.empty(label.max() + 1, dtype=np.int64)
    rank[label[keep]] = np.arange(keep.size)
    return keep, rank[label]


def apart(x: NDArray, y: NDArray, distance_px: float) -> bool:
    """Whether every two of the points (x, y) (shape (N,) each, px) lie farther than
    ``distance_px`` from each other (False when a coordinate is NaN); compares all N (N - 1) / 2
    pairs at once."""
    d2 = (x[:, None] - x) ** 2 + (y[:, None] - y) ** 2
    return bool(np.count_nonzero(d2 > distance_px**2) == len(x) * (len(x) - 1))  # all but the diagonal


def merge_coincident(details: DetectionDetails, radius_px: float = MERGE_RADIUS_PX) -> DetectionDetails:
    """``details`` with each group of coincident detections merged into one (module docstring):
    flux and area summed, peak and peak SNR the largest, the magnitude from the summed flux, the
    rest from the brightest member. Unchanged (the same object) when no two coincide."""
    det = details.detections
    keep, group = coincident_groups(det.x, det.y, det.flux, radius_px)
    if keep.size == len(det):
        return details
    n = keep.size
    flux = _group_sum(det.flux, group, n)
    kept = details.take(keep)
    with np.errstate(invalid="ignore", divide="ignore"):
        mag = kept.mag - 2.5 * np.log10(flux / kept.detections.flux)
    detections = replace(kept.detections, flux=flux, area_px=_group_sum(det.area_px, group, n),
                         peak=_group_max(det.peak, group, n))
    return replace(kept, detections=detections, mag=np.where(np.isfinite(mag), mag, kept.mag),
                   peak_snr=_group_max(details.peak_snr, group, n))


def brightest_first(details: DetectionDetails, max_stars: int | None) -> DetectionDetails:
    """Coincident detections merged, then sorted by decreasing flux and cut to ``max_stars``."""
    details = merge_coincident(details)
    order = np.argsort(-details.detections.flux, kind="stable")[:max_stars]
    return details.take(order)


def _group_sum(values: NDArray, group: NDArray[np.int64], n_groups: int) -> NDArray:
    """Per-group sums of ``values`` (N,), shape (n_groups,), in the values' dtype."""
    out = np.zeros(n_groups, dtype=values.dtype)
    np.add.at(out, group, values)
    return out


def _group_max(values: NDArray, group: NDArray[np.int64], n_groups: int) -> NDArray:
    """Per-group maxima of ``values`` (N,), shape (n_groups,) (NaN where a group has only NaN)."""
    out = np.full(n_groups, -np.inf)
    np.fmax.at(out, group, values)
    return np.where(np.isinf(out), np.nan, out)
