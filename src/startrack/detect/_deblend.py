"""Split clusters that hold two or more stars (close pairs, open clusters).

8-connected clustering (Huffman 2006 §4.2.1) merges stars whose images touch above the threshold,
and the weighted-sum centroid of such a cluster lies between the stars. A cluster is split
when its significance image has several local maxima separated by a real valley:

1. candidate peaks are the cluster's pixels that are at least as high as their 8 neighbours
   and above the detection threshold;
2. going from the highest peak down, a peak is kept when, on the straight line to every
   already-kept peak of the cluster, the significance dips below ``valley`` times its own
   height (a noise ripple on a bright star or a slightly lumpy streak does not dip);
3. every pixel of a split cluster goes to the nearest kept peak.

The loop in step 2 runs over the few clusters that have more than one candidate peak only,
and over at most :data:`MAX_PEAKS` peaks of each.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._compiled import region_kernels
from ._label import Regions, regions_from_index

DEFAULT_VALLEY = 0.7
"""A second peak counts as a star when the saddle towards a brighter one is below 70 % of it."""

MAX_PEAKS = 32
"""Only a region's highest candidate peaks are examined (bounds the cost on large blobs)."""


def local_peaks(regions: Regions, snr: NDArray, min_sigma: float) -> NDArray[np.bool_]:
    """True for region pixels that are local maxima of ``snr`` (8 neighbours, >=, indices
    clamped to the image) above ``min_sigma`` (compared in ``snr``'s type); shape (M,). One
    compiled loop (:func:`.region_kernels.local_peaks`)."""
    return region_kernels().local_peaks(regions.y, regions.x, snr, snr.dtype.type(min_sigma))


def _dips_below(snr: NDArray, a: NDArray, b: NDArray, level: float) -> bool:
    """Whether ``snr`` along the segment from pixel a to pixel b (y, x) goes below ``level``."""
    n = int(np.ceil(np.hypot(*(b - a)))) + 1
    t = np.linspace(0.0, 1.0, n)
    ys = np.rint(a[0] + t * (b[0] - a[0])).astype(np.int64)
    xs = np.rint(a[1] + t * (b[1] - a[1])).astype(np.int64)
    return bool(snr[ys, xs].min() < level)


def _kept_peaks(snr: NDArray, peaks_yx: NDArray, valley: float) -> NDArray[np.int64]:
    """Rows of ``peaks_yx`` (one cluster's candidates, highest first) that are separate stars."""
    kept = [0]
    for i in range(1, len(peaks_yx)):
        level = valley * snr[peaks_yx[i, 0], peaks_yx[i, 1]]
        if all(_dips_below(snr, peaks_yx[k], peaks_yx[i], level) for k in kept):
            kept.append(i)
    return np.array(kept)


def split_regions(regions: Regions, snr: NDArray, min_sigma: float,
                  valley: float = DEFAULT_VALLEY) -> Regions:
    """Split multi-star regions (module docstring); regions with one star are unchanged.

    Parameters
    ----------
    regions : Regions
        Clusters on the grid of ``snr``.
    snr : ndarray, shape (h, w)
        Significance image the clusters were found on.
    min_sigma : float
        Lowest significance of a peak (the detection threshold).
    valley : float
        Saddle-to-peak ratio below which two peaks are separate stars.

    Returns
    -------
    Regions
        Split clusters get new numbers after the existing ones; numbering is then compacted.
    """
    is_peak = local_peaks(regions, snr, min_sigma)
    n_peaks = np.bincount(regions.index[is_peak], minlength=len(regions))
    multi = np.flatnonzero(n_peaks > 1)
    if multi.size == 0:
        return regions
    index = regions.index.copy()
    n_total = len(regions)
    for r in multi:
        n_total = _split_one(regions, snr, is_peak, int(r), valley, index, n_total)
    used, index = np.unique(index, return_inverse=True)
    return regions_from_index(index, regions.y, regions.x, used.size)


def _split_one(regions: Regions, snr: NDArray, is_peak: NDArray, r: int, valley: float,
               index: NDArray, n_total: int) -> int:
    """Split region ``r`` in place in ``index``; returns the new number of regions."""
    lo, hi = regions.starts[r], regions.starts[r] + regions.counts[r]
    ys, xs = regions.y[lo:hi], regions.x[lo:hi]
    peaks = np.flatnonzero(is_peak[lo:hi])
    peaks = peaks[np.argsort(-snr[ys[peaks], xs[peaks]], kind="stable")][:MAX_PEAKS]
    peaks_yx = np.stack([ys[peaks], xs[peaks]], axis=1)
    kept = peaks_yx[_kept_peaks(snr, peaks_yx, valley)]
    if len(kept) < 2:
        return n_total
    d2 = (ys[:, None] - kept[:, 0]) ** 2 + (xs[:, None] - kept[:, 1]) ** 2
    owner = np.argmin(d2, axis=1)
    new_numbers = np.concatenate([[r], n_total + np.arange(len(kept) - 1)])
    index[lo:hi] = new_numbers[owner]
    return n_total + len(kept) - 1
