"""Hot pixels replaced before detection, where they are most of a frame's spots.

A sensor's hot pixels stand alone, far brighter than their neighbours, or in pairs and triples
once a colour photo is demosaiced. The spot filters refuse them one spot at a time
(:func:`._filters.peak_fractions`), but where they are many (a warm, uncooled sensor in a long
exposure; a detector damaged by radiation) they do harm before that: the 2 x 2 binning and the
3 x 3 smoothing of the detection image spread each over about a dozen of its pixels, and the
tiles' noise (the width of their 15.87-84.13 % quantiles) grows several times, and the threshold
with it, over most of the stars (10.4 against 1.7 on an openstartracker frame with 1 % of its
pixels hot; 3 of its 16 matched stars were found).

So when the hot spots are at least half of the first pass's spots, and at least
:data:`._filters.HOT_PIXELS_ABOUND` (:func:`hot_pixels_dominate`), they are replaced
(:func:`without_hot_pixels`) and the frame is detected again: around every local maximum of the
full-resolution plane that stands :data:`HOT_SIGMA` times the pixel noise over the background
level and whose 3 x 3 neighbourhood the hot-pixel tests refuse (the peak's share of the 3 x 3 sum,
or the measure of pairs, triples and blocks, over ``max_peak_fraction``), the pixels of the
neighbourhood over that threshold take the median of the 16 pixels around it (:data:`RING_5X5`;
a block of five or six is most of its own 3 x 3, whose median would be one of its pixels). This
is the cosmetic correction of astronomical image processing (a median replaces pixels that stand
alone; van Dokkum 2001, L.A.Cosmic, finds cosmic rays by their sharp edges in the same spirit),
run only where the spots say it is needed, so that every other frame is detected exactly as
before.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._filters import HotMeasures, hot_pixel_ok, hot_pixels_abound, neighbourhoods_3x3, peak_fractions

RING_5X5 = np.array([(dy, dx) for dy in range(-2, 3) for dx in range(-2, 3) if max(abs(dy), abs(dx)) == 2])
"""Offsets (dy, dx) of the 16 pixels around a 3 x 3 neighbourhood, shape (16, 2)."""

HOT_SIGMA = 5.0
"""A local maximum is replaced when it stands this many times the pixel noise over the level
(and its neighbourhood is refused by the hot-pixel tests); fainter hot pixels do not raise the
detection image's noise much."""

CLEAN_PASSES = 2
"""Replacement passes: the second finds the hot pixels a brighter hot neighbour hid from the
first (a local maximum is the brightest of its 3 x 3 neighbourhood)."""


def refused(single: NDArray, cluster: NDArray, max_peak_fraction: float) -> NDArray[np.bool_]:
    """Shape (N,): the spots the hot-pixel tests refuse, from their peak fractions ``single``
    and cluster measures ``cluster`` (:func:`._filters.peak_fractions`)."""
    return ~(hot_pixel_ok(single, max_peak_fraction) & hot_pixel_ok(cluster, max_peak_fraction))


def hot_pixels_dominate(measures: HotMeasures, max_peak_fraction: float | None) -> bool:
    """Whether hot pixels, alone or in pairs and triples, are at least half of a frame's N spots
    (their ``measures``, shape (N,) each; blocks of four to six do not count,
    :func:`._filters.peak_fraction`) and at least :data:`._filters.HOT_PIXELS_ABOUND` of them:
    :func:`._filters.hot_pixels_abound` against the other spots (never when the test is off,
    ``max_peak_fraction`` None)."""
    if max_peak_fraction is None:
        return False
    hot = refused(measures.single, measures.cluster, max_peak_fraction)
    return hot_pixels_abound(hot, ~hot)


def without_hot_pixels(data: NDArray, level: NDArray, noise_px: float,
                       max_peak_fraction: float) -> NDArray[np.float32]:
    """A float32 copy of the plane ``data`` (H, W) with its hot pixels replaced (module
    docstring); ``level`` (H, W) is the background level and ``noise_px`` the pixel noise, in the
    plane's units. NaN pixels stay NaN and are never a local maximum."""
    values = data.astype(np.float32)  # a copy
    threshold = HOT_SIGMA * noise_px
    for _ in range(CLEAN_PASSES):
        y, x = _bright_maxima(values, level, threshold)
        measures = peak_fractions(values, level[y, x], x, y, noise=noise_px)
        hot = refused(measures.single, measures.block, max_peak_fraction)
        if not hot.any():
            break
        _replace(values, level, y[hot], x[hot], threshold)
    return values


def _bright_maxima(values: NDArray, level: NDArray, threshold: float) -> tuple[NDArray, NDArray]:
    """Rows and columns (K,) of the pixels that are the largest of their 3 x 3 neighbourhood and
    stand more than ``threshold`` over the level."""
    from scipy import ndimage  # only frames with many hot pixels come here

    finite = np.where(np.isnan(values), -np.inf, values)
    peak = (finite >= ndimage.maximum_filter(finite, size=3, mode="nearest")) & (values - level > threshold)
    rows, cols = np.nonzero(peak)
    return rows, cols


def _replace(values: NDArray, level: NDArray, y: NDArray, x: NDArray, threshold: float) -> None:
    """Set, in place, the pixels of the 3 x 3 neighbourhoods about (y, x) (K,) that stand more
    than ``threshold`` over the level to the median of the ring around them (:data:`RING_5X5`)."""
    ys, xs = neighbourhoods_3x3(values.shape, y, x)
    window = values[ys, xs]  # (K, 9)
    median = np.nanmedian(values[neighbourhoods_3x3(values.shape, y, x, RING_5X5)], axis=1)
    with np.errstate(invalid="ignore"):
        high = window - level[ys, xs] > threshold
    values[ys[high], xs[high]] = np.broadcast_to(median[:, None], window.shape)[high]
