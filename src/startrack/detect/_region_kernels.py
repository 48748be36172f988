"""The compiled loops over the pixel lists of :class:`.label.Regions` (numba): per-region
weighted moments, the shapes of the half-maximum cores and signal sums (each region's pixels in
two short passes), the local peaks of the deblender, and the hot-pixel measures of the spots'
3 x 3 neighbourhoods (:func:`hot_measures`, for :func:`.filters.peak_fractions`).

They give the values of the numpy expressions of :func:`.centroid.measure_spots`,
:func:`.point_source.core_shape` and :func:`.deblend.local_peaks` that they replace, sums taken
pixel after pixel (numpy's ``np.add.reduceat`` sums a long region pairwise, so the two may
differ in the last bits; ``tests/detect/test_detect_region_kernels.py`` keeps the numpy versions
as the reference). Loaded on first use through
:func:`.compiled.region_kernels`; cached on disk (``cache=True``); numpy's error model (0 / 0 is
NaN, as in numpy).
"""

from __future__ import annotations

import numpy as np
from numba import njit

MOMENTS = 7
"""Columns of :func:`weighted_moments`: sum of weights, mean x, mean y, the weighted central
moments xx, yy and xy (each over the sum of weights), and the spread of the positive-weight
pixels."""


@njit(cache=True, error_model="numpy")
def weighted_moments(starts, x, y, w):
    """Weighted moments of N regions.

    ``starts`` (N,) int64, the regions' first pixels in ``x``, ``y``, ``w`` (M,) float64: pixel
    column, row and weight. Returns (N, :data:`MOMENTS`) float64: per region ``W = sum w``, the
    means ``mx = sum w x / W``, ``my``, then ``sum w dx dx / W``, ``sum w dy dy / W``,
    ``sum w dx dy / W`` (dx = x - mx, dy = y - my) and ``sum dx dx + dy dy`` over the pixels
    with ``w > 0``."""
    n = starts.size
    out = np.empty((n, MOMENTS))
    for r in range(n):
        _region_moments(x, y, w, starts[r], starts[r + 1] if r + 1 < n else x.size, out[r])
    return out


@njit(cache=True, error_model="numpy")
def _region_moments(x, y, w, lo, hi, out):
    """:func:`weighted_moments` of the one region of pixels ``lo`` .. ``hi`` - 1, written into
    ``out`` (:data:`MOMENTS`,)."""
    total = sx = sy = 0.0
    for p in range(lo, hi):
        total += w[p]
        sx += w[p] * x[p]
        sy += w[p] * y[p]
    mx, my = sx / total, sy / total
    cxx = cyy = cxy = spread = 0.0
    for p in range(lo, hi):
        dx, dy = x[p] - mx, y[p] - my
        cxx += w[p] * dx * dx
        cyy += w[p] * dy * dy
        cxy += w[p] * dx * dy
        if w[p] > 0:
            spread += dx * dx + dy * dy
    out[0], out[1], out[2] = total, mx, my
    out[3], out[4], out[5], out[6] = cxx / total, cyy / total, cxy / total, spread


@njit(cache=True, error_model="numpy")
def core_shapes(starts, x, y, signal, peak, min_pixels, half_max_area):
    """Half-maximum size, elongation and fill of the cores of N regions, the numbers of the numpy
    expressions of :func:`.point_source.core_shape` operation for operation.

    ``starts`` (N,) as in :func:`weighted_moments`; ``x``, ``y`` (M,) int64 pixel columns and rows,
    ``signal`` (M,) float64, ``peak`` (N,) float64 each region's largest signal; a region's core
    is its pixels with ``signal >= 0.5 peak`` (none where ``peak`` is NaN). ``min_pixels``: the
    elongation and fill of smaller cores are 1; ``half_max_area`` the core area of a Gaussian of
    unit standard deviation, px^2. Returns (3, N) float64: ``sqrt(area / half_max_area)`` (px),
    the ratio of the principal axes of the core's second moments (each plus 1/12 px^2 on the
    diagonal) and ``area / (4 pi sqrt(det))``.
    """
    n = starts.size
    out = np.empty((3, n))
    for r in range(n):
        hi = starts[r + 1] if r + 1 < n else x.size
        area, cxx, cyy, cxy = _core_moments(x, y, signal, 0.5 * peak[r], starts[r], hi)
        out[0, r], out[1, r], out[2, r] = np.sqrt(area / half_max_area), 1.0, 1.0
        if area >= min_pixels:
            xx, yy = cxx + 1.0 / 12.0, cyy + 1.0 / 12.0
            det = xx * yy - cxy * cxy
            out[1, r] = _axis_ratio(xx, yy, cxy)
            out[2, r] = area / (4.0 * np.pi * np.sqrt(det if det > 0.0 else 0.0))
    return out


@njit(cache=True, error_model="numpy")
def _core_moments(x, y, signal, half, lo, hi):
    """Pixel count and central moments xx, yy, xy over the count of the pixels ``lo`` .. ``hi`` - 1
    with ``signal >= half``: :func:`_region_moments`' with the weights 1 on them and 0 elsewhere,
    bit for bit (a zero weight adds a zero to a sum that is never -0); NaN moments when none."""
    count = sx = sy = 0.0
    for p in range(lo, hi):
        if signal[p] >= half:  # False against NaN
            count += 1.0
            sx += np.float64(x[p])
            sy += np.float64(y[p])
    mx, my = sx / count, sy / count
    cxx = cyy = cxy = 0.0
    for p in range(lo, hi):
        if signal[p] >= half:
            dx, dy = x[p] - mx, y[p] - my
            cxx += dx * dx
            cyy += dy * dy
            cxy += dx * dy
    return count, cxx / count, cyy / count, cxy / count


@njit(cache=True, error_model="numpy")
def _axis_ratio(cxx, cyy, cxy):
    """:func:`.centroid.axis_ratio` of one finite moment matrix [[cxx, cxy], [cxy, cyy]]."""
    mean = 0.5 * (cxx + cyy)
    half_diff = np.sqrt(0.25 * ((cxx - cyy) * (cxx - cyy)) + cxy * cxy)
    low = mean - half_diff
    return np.sqrt((mean + half_diff) / (low if low > 1e-12 else 1e-12))


@njit(cache=True, error_model="numpy")
def signal_sums(starts, signal):
    """Sum and sum of squares of ``signal`` (M,) float64 over N regions (``starts`` as in
    :func:`weighted_moments`), (N, 2) float64, and the position of each region's largest value,
    (N,) int64: the last of equal largest values, or the last NaN when the region has one
    (``np.maximum.reduceat``'s largest, as :meth:`.label.Regions.argmax`)."""
    n = starts.size
    sums = np.empty((n, 2))
    top = np.empty(n, np.int64)
    for r in range(n):
        lo, hi = starts[r], starts[r + 1] if r + 1 < n else signal.size
        total = squares = 0.0
        for p in range(lo, hi):
            v = signal[p]
            total += v
            squares += v * v
        sums[r, 0], sums[r, 1], top[r] = total, squares, _last_largest(signal, lo, hi)
    return sums, top


@njit(cache=True, error_model="numpy")
def _last_largest(values, lo, hi):
    """Position of the largest of ``values[lo:hi]``: the last of equal largest values, or the last
    NaN when there is one (:meth:`.label.Regions.argmax`); ``lo`` when the range is empty."""
    best, where, has_nan = -np.inf, lo, False
    for p in range(lo, hi):
        v = values[p]
        if np.isnan(v):
            where, has_nan = p, True
        elif not has_nan and v >= best:
            best, where = v, p
    return where


@njit(cache=True, error_model="numpy")
def image_max(starts, y, x, image):
    """Largest value of ``image`` (h, w) over the pixels (``y``, ``x``) (M,) of each of N regions
    (``starts`` as in :func:`weighted_moments`; every region has a pixel), in the image's type
    (N,): ``np.maximum.reduceat(image[y, x], starts)`` (NaN when a pixel is NaN)."""
    n = starts.size
    out = np.empty(n, image.dtype)
    for r in range(n):
        lo, hi = starts[r], starts[r + 1] if r + 1 < n else y.size
        best = image[y[lo], x[lo]]
        for p in range(lo + 1, hi):
            v = image[y[p], x[p]]
            if not (np.isnan(best) or v <= best):  # np.maximum: NaN wins, a tie keeps the first
                best = v
        out[r] = best
    return out


@njit(cache=True, error_model="numpy")
def select_pixels(index, y, x, starts, keep):
    """The arrays of :meth:`.label.Regions.select`: the pixels ``index``, ``y``, ``x`` (M,) of the
    N regions (``starts`` (N,)) where ``keep`` (N,) is True, the regions renumbered 0 .. K-1 in
    their order; returns (index, y, x) (M',) and starts (K,), int64 (``y`` and ``x`` in their
    own types)."""
    n = starts.size
    new_number = np.empty(n, np.int64)
    kept, total = 0, 0
    for r in range(n):
        new_number[r] = kept
        kept += keep[r]
    for p in range(index.size):
        total += keep[index[p]]
    out_index, out_y, out_x = np.empty(total, np.int64), np.empty(total, y.dtype), np.empty(total, x.dtype)
    q = 0
    for p in range(index.size):
        if keep[index[p]]:
            out_index[q], out_y[q], out_x[q] = new_number[index[p]], y[p], x[p]
            q += 1
    out_starts = np.empty(kept, np.int64)
    q = 0
    for r in range(n):
        if keep[r]:
            out_starts[new_number[r]] = q
            q += (starts[r + 1] if r + 1 < n else index.size) - starts[r]
    return out_index, out_y, out_x, out_starts


@njit(cache=True, error_model="numpy")
def upsample_pixels(index, y, x, factor):
    """The pixels of :meth:`.label.Regions.upsample`: each pixel (``y``, ``x``) (M,) of region
    ``index`` becomes the ``factor`` x ``factor`` block of full-resolution pixels it was binned
    from, row by row; returns (index, y, x) (M factor^2,) int64."""
    n = factor * factor
    out = np.empty((3, y.size * n), np.int64)
    out_index, out_y, out_x = out[0], out[1], out[2]
    for p in range(y.size):
        for d in range(n):
            q = p * n + d
            out_index[q], out_y[q], out_x[q] = index[p], y[p] * factor + d // factor, x[p] * factor + d % factor
    return out_index, out_y, out_x


@njit(cache=True, error_model="numpy")
def edge_keep(starts, y, x, values, core, h, w, margin, max_core, peak_fraction):
    """:func:`.filters.peak_away_from_edge` of N regions (``starts`` as in
    :func:`weighted_moments``; pixels ``y``, ``x``, ``values`` and bool ``core`` (M,)) on an image
    ``h`` x ``w``: (N,) bool, True where no core pixel of at least ``peak_fraction`` times the
    region's highest value (:func:`_last_largest`) lies on the border, or that value lies
    ``margin`` pixels or more inside and the region has at most ``max_core`` core pixels."""
    n = starts.size
    out = np.empty(n, np.bool_)
    for r in range(n):
        lo, hi = starts[r], starts[r + 1] if r + 1 < n else y.size
        top = _last_largest(values, lo, hi)
        inside = margin <= y[top] < h - margin and margin <= x[top] < w - margin
        level = peak_fraction * values[top]
        n_core, touches = 0, False
        for p in range(lo, hi):
            if core[p]:
                n_core += 1
                on_border = y[p] == 0 or y[p] == h - 1 or x[p] == 0 or x[p] == w - 1
                touches = touches or (on_border and not values[p] < level)  # a NaN peak: every pixel
        out[r] = not touches or (inside and n_core <= max_core)
    return out


@njit(cache=True, error_model="numpy")
def local_peaks(y, x, snr, min_sigma):
    """Which pixels (``y``, ``x``) (M,) int64 of the image ``snr`` (h, w) are above ``min_sigma``
    (of ``snr``'s type) and at least as high as each of their 8 neighbours (indices clamped to
    the image): (M,) bool, :func:`.deblend.local_peaks`."""
    h, w = snr.shape
    out = np.empty(y.size, np.bool_)
    for p in range(y.size):
        v = snr[y[p], x[p]]
        peak = v > min_sigma
        for dy in range(-1, 2):
            row = min(max(y[p] + dy, 0), h - 1)
            for dx in range(-1, 2):
                if peak and (dy != 0 or dx != 0):
                    peak = v >= snr[row, min(max(x[p] + dx, 0), w - 1)]  # False against NaN
        out[p] = peak
    return out


@njit(cache=True, error_model="numpy")
def spot_axes(starts, x, y):
    """Jacobs 1995 axes of N regions (``starts`` as in :func:`weighted_moments`; ``x``, ``y`` (M,)
    float64 pixel columns and rows), :func:`.shape.spot_shape`: (N, 3) float64, the extent along
    and across the direction of the unweighted second moments (plus one pixel) and that
    direction, radians in [-pi/2, pi/2]."""
    n = starts.size
    out = np.empty((n, 3))
    ones, m = np.ones(x.size), np.empty(MOMENTS)
    for r in range(n):
        lo, hi = starts[r], starts[r + 1] if r + 1 < n else x.size
        _region_moments(x, y, ones, lo, hi, m)  # unweighted: the moments over the count
        x0, y0 = m[1], m[2]
        angle = 0.5 * np.arctan2(2.0 * m[5], m[3] - m[4])
        c, s = np.cos(angle), np.sin(angle)
        a_lo = a_hi = b_lo = b_hi = 0.0
        for p in range(lo, hi):
            dx, dy = x[p] - x0, y[p] - y0
            along, across = dx * c + dy * s, -dx * s + dy * c
            if p == lo or along < a_lo:
                a_lo = along
            if p == lo or along > a_hi:
                a_hi = along
            if p == lo or across < b_lo:
                b_lo = across
            if p == lo or across > b_hi:
                b_hi = across
        out[r, 0], out[r, 1], out[r, 2] = a_hi - a_lo + 1.0, b_hi - b_lo + 1.0, angle
    return out


@njit(cache=True, error_model="numpy")
def hot_measures(window, peak, noise, cluster_pixels, block_min_snr, out):
    """The hot-pixel measures of N spots into ``out`` (3, N) float64 (single, cluster, block) of
    :func:`.filters.peak_fractions`, from the background-subtracted 3 x 3 neighbourhood of each
    spot's peak, ``window`` (N, 9) float64 (row-major, the peak in the middle), and the peak
    ``peak`` (N,): clusters of up to ``cluster_pixels`` pixels, then blocks of one more pixel for
    each of ``block_min_snr`` (B,), judged where the sum reaches that many times ``noise`` (N,).
    The numbers are those of the numpy expressions this loop replaced: the sum in numpy's order
    for nine values (:func:`_sum9`), NaN pixels as 0 in it and last in the ranking, and the
    brightest after the largest summed in turn before the peak is added (numpy's cumsum)."""
    ranked = np.empty(9)
    for k in range(peak.size):
        total = _sum9(window[k])
        single = peak[k] / total
        out[0, k] = single
        if not total > 0:
            out[1, k] = out[2, k] = single
            continue
        for i in range(9):
            ranked[i] = -np.inf if np.isnan(window[k, i]) else window[k, i]
        ranked.sort()
        cluster, block, brighter = single, 0.0, 0.0
        for j in range(1, cluster_pixels + block_min_snr.size):  # j + 1 pixels
            brighter += max(ranked[8 - j], 0.0)
            powered = ((peak[k] + brighter) / total) ** (2.0 ** j)
            if j < cluster_pixels:
                cluster = max(cluster, powered)
            elif total >= noise[k] * block_min_snr[j - cluster_pixels]:
                block = max(block, powered)
        out[1, k], out[2, k] = cluster, max(cluster, block)


@njit(cache=True, error_model="numpy")
def _sum9(values):
    """The sum of nine float64 values, NaN as 0, in the order of numpy's pairwise sum of a row of
    nine (eight accumulators paired, then the ninth), so that the result is numpy's bit for bit."""
    v = np.empty(9)
    for i in range(9):
        v[i] = 0.0 if np.isnan(values[i]) else values[i]
    return ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7])) + v[8]
