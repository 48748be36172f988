"""The compiled loops of :mod:`._robust` (numba): the quantization step of integer-valued samples
and the clipped level and noise of quantized samples, from a histogram of their bins.

Each loop gives the numbers of the numpy expressions it replaces (the same bins, the same
cumulative fractions, the interpolation of ``np.interp`` case for case), so the statistics do not
depend on which one ran; one pass over the samples per step instead of a dozen numpy temporaries.
Loaded on first use through :func:`.compiled.robust_kernels`; cached on disk (``cache=True``);
numpy's error model.
"""

from __future__ import annotations

import numpy as np
from numba import njit

GCD_PROBE = 256
"""Values whose distances :func:`quantization_step` tries first (:func:`_coprime_start`)."""


@njit(cache=True, error_model="numpy")
def quantization_step(values, max_range):
    """:func:`.robust.quantization_step` of float64 ``values`` (N,), N >= 2: 0 unless every value
    is an integer, 1 when they span more than ``max_range`` or take one value, else the greatest
    common divisor of the gaps between the values present."""
    lo, hi = np.inf, -np.inf
    for v in values:
        if np.floor(v) != v:  # NaN too
            return 0.0
        lo, hi = min(lo, v), max(hi, v)
    if hi - lo > max_range or _coprime_start(values, lo):
        return 1.0
    present = np.zeros(int(hi - lo) + 1, dtype=np.bool_)
    for v in values:
        present[int(v - lo)] = True
    divisor, last = 0, -1
    for k in range(present.size):
        if present[k]:
            if last >= 0:
                divisor = _gcd(divisor, k - last)
            last = k
    return 1.0 if last < 0 or divisor == 0 else float(max(1, divisor))


@njit(cache=True, error_model="numpy")
def _coprime_start(values, lo):
    """Whether the distances from ``lo`` (the smallest) of the first :data:`GCD_PROBE` of the
    integer ``values`` (their span at most :data:`.robust.MAX_QUANTIZED_RANGE`) have no common
    divisor but 1: then neither have the gaps between all the values present (the gaps' greatest
    common divisor is the distances'), so that the step of noisy data is found without a pass
    over its histogram."""
    divisor = 0
    for p in range(min(values.size, GCD_PROBE)):
        divisor = _gcd(divisor, int(values[p] - lo))
        if divisor == 1:
            return True
    return False


@njit(cache=True, error_model="numpy")
def _gcd(a, b):
    """Greatest common divisor of non-negative integers (``gcd(0, b) = b``)."""
    while b:
        a, b = b, a % b
    return a


@njit(cache=True, error_model="numpy")
def clipped_quantized(values, step, upper_half, probabilities, clip_sigma, iterations, max_range):
    """:func:`.robust.clipped_level_noise` of float64 ``values`` (N,), N >= 1, on a grid of
    ``step`` > 0; ``probabilities`` (3,) are the low, median and high quantiles. Returns
    ``(level, noise, done)``: ``done`` is False (and nothing measured) when the values span more
    than ``max_range`` steps, which the caller measures with plain quantiles."""
    lo, hi = _span(values)
    if (hi - lo) / step > max_range:
        return 0.0, 0.0, False
    counts = _grid_counts(values, lo, hi, step)
    if counts.size:
        level, noise = _clipped_bins(counts, lo, step, upper_half, probabilities, clip_sigma, iterations)
        return level, noise, True
    level, noise = 0.0, 0.0
    for _ in range(iterations):
        q_lo, level, q_hi = _grouped_quantiles(values, step, probabilities)
        noise = (q_hi - level) if upper_half else 0.5 * (q_hi - q_lo)
        noise = np.sqrt(max(noise**2 - step**2 / 12.0, 0.0))
        if noise <= 0:
            break
        kept = values[np.abs(values - level) <= clip_sigma * noise]
        if kept.size == values.size or kept.size < 3:
            break
        values = kept
    return level, max(noise, 0.0), True


@njit(cache=True, error_model="numpy")
def _grid_counts(values, lo, hi, step):
    """How many of ``values`` fall on each grid value ``lo + step k``, k = 0 .. (hi - lo) / step,
    when every value is an integer below 2^52 that lies exactly on the grid (so that the
    arithmetic of the clipping loop is exact whether it runs on values or on bins); else empty.
    ``lo`` and ``hi`` are the smallest and largest value (:func:`_span`)."""
    empty = np.zeros(0, dtype=np.int64)
    if np.floor(step) != step or max(abs(lo), abs(hi)) >= 2.0**52 or np.floor(lo) != lo:
        return empty
    counts = np.zeros(int(np.rint((hi - lo) / step)) + 1, dtype=np.int64)
    unit = step == 1.0  # no division: v - lo is the bin of an integer v
    for v in values:
        k = int(v - lo) if unit else int(np.rint((v - lo) / step))
        if lo + step * k != v:  # an integer (exact below 2^53), so also where v is not one (or NaN)
            return empty
        counts[k] += 1
    return counts


@njit(cache=True, error_model="numpy")
def _clipped_bins(counts, lo, step, upper_half, probabilities, clip_sigma, iterations):
    """The clipping loop of :func:`clipped_quantized` on the grid's counts (:func:`_grid_counts`):
    the values kept are those of a range of bins, narrowed each time."""
    first, last, n = 0, counts.size - 1, counts.sum()
    level, noise = 0.0, 0.0
    for _ in range(iterations):
        q_lo, level, q_hi = _bin_quantiles(counts, first, last, n, lo + step * first, step, probabilities)
        noise = (q_hi - level) if upper_half else 0.5 * (q_hi - q_lo)
        noise = np.sqrt(max(noise**2 - step**2 / 12.0, 0.0))
        if noise <= 0:
            break
        kept_first, kept_last, kept = last + 1, first - 1, 0
        for k in range(first, last + 1):
            if counts[k] > 0 and np.abs((lo + step * k) - level) <= clip_sigma * noise:
                kept_first, kept_last, kept = min(kept_first, k), k, kept + counts[k]
        if kept == n or kept < 3:
            break
        first, last, n = kept_first, kept_last, kept
    return level, max(noise, 0.0)


@njit(cache=True, error_model="numpy")
def _bin_quantiles(counts, first, last, n, lo, step, probabilities):
    """:func:`_grouped_quantiles` of the ``n`` values in bins ``first .. last`` of ``counts``
    (both present), the smallest of them ``lo``."""
    n_present = 0
    for k in range(first, last + 1):
        n_present += counts[k] > 0
    cdf, edges = np.zeros(n_present + 1), np.empty(n_present + 1)
    i, total = 0, 0
    for k in range(first, last + 1):
        if counts[k] > 0:
            total += counts[k]
            edges[i] = (lo + step * (k - first)) - step / 2
            i += 1
            cdf[i] = total / n
    edges[n_present] = (lo + step * (last - first)) + step / 2
    return (_interp(probabilities[0], cdf, edges), _interp(probabilities[1], cdf, edges),
            _interp(probabilities[2], cdf, edges))


@njit(cache=True, error_model="numpy")
def _span(values):
    """Smallest and largest of ``values``."""
    lo, hi = np.inf, -np.inf
    for v in values:
        lo, hi = min(lo, v), max(hi, v)
    return lo, hi


@njit(cache=True, error_model="numpy")
def _grouped_quantiles(values, step, probabilities):
    """:func:`.robust.quantiles` of quantized ``values`` (3 probabilities): the cumulative
    fraction at the edges of the bins present, interpolated as ``np.interp`` does."""
    lo, hi = _span(values)
    counts = np.zeros(int(np.rint((hi - lo) / step)) + 1, dtype=np.int64)
    for v in values:
        counts[int(np.rint((v - lo) / step))] += 1
    n_present = 0
    for c in counts:
        n_present += c > 0
    cdf, edges = np.zeros(n_present + 1), np.empty(n_present + 1)
    k, total = 0, 0
    for b in range(counts.size):
        if counts[b] > 0:
            total += counts[b]
            edges[k] = (lo + step * b) - step / 2
            k += 1
            cdf[k] = total / values.size
    edges[n_present] = (lo + step * (counts.size - 1)) + step / 2
    return (_interp(probabilities[0], cdf, edges), _interp(probabilities[1], cdf, edges),
            _interp(probabilities[2], cdf, edges))


@njit(cache=True, error_model="numpy")
def _interp(x, xp, fp):
    """``np.interp(x, xp, fp)`` for one finite ``x`` and strictly increasing ``xp``: numpy's cases
    (the end values beyond the ends, ``fp[j]`` at a knot, else ``slope (x - xp[j]) + fp[j]``)."""
    last = xp.size - 1
    if x < xp[0]:
        return fp[0]
    if x >= xp[last]:
        return fp[last]
    j = np.searchsorted(xp, x, side="right") - 1
    if xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    result = slope * (x - xp[j]) + fp[j]
    if np.isnan(result):
        result = slope * (x - xp[j + 1]) + fp[j + 1]
        if np.isnan(result) and fp[j] == fp[j + 1]:
            result = fp[j]
    return result
