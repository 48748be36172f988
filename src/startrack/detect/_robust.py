"""Robust statistics of pixel samples: quantiles of quantized data, clipped level and noise.

* **level** = median; **noise** = half the 15.87-84.13 % interquantile range (the standard
  deviation of a Gaussian), after iterative 3-sigma clipping, so that stars and hot pixels
  barely move either;
* for raw pixels whose low side the camera clips at 0, the **upper-half** width
  (84.13 % quantile - median) is used instead;
* integer-valued data are treated as quantized: each value stands for a bin of the
  quantization step, and quantiles are interpolated within the bins (a 1-DN noise is measured
  correctly instead of jumping between 0 and 1). Spreading the values over their bins adds
  step^2 / 12 to the variance, which is taken off again, so the result is the standard
  deviation of the quantized values themselves (Sheppard: sigma^2 + step^2 / 12).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._compiled import robust_kernels

GAUSS_LO, GAUSS_HI = 0.15865525393145707, 0.8413447460685429
"""Quantiles at -1 and +1 sigma of a normal distribution."""

MAX_SAMPLES = 1 << 15
"""Pixels used for whole-image statistics (a strided subsample)."""

CLIP_SIGMA = 3.0
CLIP_ITERATIONS = 3
MAX_QUANTIZED_RANGE = 1 << 20
"""Above this many quantization steps between min and max, plain quantiles are used."""


def strided_sample(image: NDArray, max_samples: int = MAX_SAMPLES) -> tuple[NDArray, int]:
    """A regular subsample ``image[::step, ::step]`` of about ``max_samples`` pixels, and step."""
    step = max(1, int(np.ceil(np.sqrt(image.size / max_samples))))
    return image[::step, ::step], step


def quantization_step(values: NDArray) -> float:
    """Spacing of the values if they all lie on a grid of integers, else 0 (1-D input)."""
    if values.size < 2:
        return 0.0
    return robust_kernels().quantization_step(np.ascontiguousarray(values, dtype=np.float64).ravel(),
                                              float(MAX_QUANTIZED_RANGE))


def quantiles(values: NDArray, q: NDArray, step: float = 0.0) -> NDArray[np.float64]:
    """Quantiles of the 1-D non-empty ``values``; for quantized data (``step`` > 0)
    interpolated within bins.

    Each quantized value v is taken as spread uniformly over [v - step/2, v + step/2], so the
    quantile is a continuous function of the data (the "grouped data" median of statistics
    textbooks).
    """
    lo, hi = float(values.min()), float(values.max())
    if step <= 0 or (hi - lo) / step > MAX_QUANTIZED_RANGE:
        return np.quantile(values, q)
    counts = np.bincount(np.rint((values - lo) / step).astype(np.int64))
    present = np.flatnonzero(counts)
    centres = lo + step * present
    cdf = np.concatenate([[0.0], np.cumsum(counts[present]) / values.size])
    edges = np.concatenate([centres - step / 2, [centres[-1] + step / 2]])
    return np.interp(q, cdf, edges)


def clipped_level_noise(values: NDArray, step: float = 0.0, upper_half: bool = False
                        ) -> tuple[float, float]:
    """Median and robust standard deviation of ``values`` after iterative 3-sigma clipping.

    Parameters
    ----------
    values : ndarray, not empty
    step : float
        Quantization step of the data (0 for continuous data), see :func:`quantiles`.
    upper_half : bool
        Measure the width from the median to the 84.13 % quantile only (for data whose low
        side is clipped); otherwise half the 15.87-84.13 % range.

    Returns
    -------
    level, noise : float
    """
    values = values.ravel()
    if step > 0:
        level, noise, done = robust_kernels().clipped_quantized(
            np.ascontiguousarray(values, dtype=np.float64), float(step), bool(upper_half),
            np.array([GAUSS_LO, 0.5, GAUSS_HI]), CLIP_SIGMA, CLIP_ITERATIONS, float(MAX_QUANTIZED_RANGE))
        if done:  # one compiled loop (:mod:`._robust_kernels`), the numbers of the loop below
            return float(level), float(noise)
    level, noise = 0.0, 0.0
    for _ in range(CLIP_ITERATIONS):
        q_lo, level, q_hi = quantiles(values, np.array([GAUSS_LO, 0.5, GAUSS_HI]), step)
        noise = (q_hi - level) if upper_half else 0.5 * (q_hi - q_lo)
        noise = np.sqrt(max(noise**2 - step**2 / 12.0, 0.0))  # the in-bin spread (see below)
        if noise <= 0:
            break
        kept = values[np.abs(values - level) <= CLIP_SIGMA * noise]
        if kept.size == values.size or kept.size < 3:
            break
        values = kept
    return float(level), float(max(noise, 0.0))
