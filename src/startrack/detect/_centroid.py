"""Weighted-sum centroids, spot shape and centroid uncertainty.

Centroid (Huffman 2006 §4.2.2 eq. 4.1; Fowler 2013 eq. 3.3)::

    x_c = sum_i w_i x_i / sum_i w_i,    w_i = max(I_i - B_i, 0)

over the full-resolution pixels i of a spot, with I the pixel value and B the local background;
pixel coordinates are pixel centres (our convention). Clipping the weights at 0 keeps
negative noise pixels of the spot's rim from pushing the centroid away.

Shape: the intensity-weighted second central moments, plus 1/12 px^2 on the diagonal for the
pixel's own extent (the ``regionprops`` convention of Fowler 2013 §II.B.6). ``elongation`` is the
ratio of the principal axes, sqrt(lambda_max / lambda_min): 1 for a round spot, large for a
streak (Huffman 2006's "aspect ratio").

Uncertainty, two models (per axis, 1 sigma, pixels):

* ``"eq4.2"`` -- Huffman 2006 §4.2.2 eq. 4.2 (Huffman 2006 §4.2.2, eq. 4.2), the empirical Monte-Carlo fit
  ``sigma = 0.11 + 0.5 * SNR**-1.3`` with SNR = peak pixel / pixel noise (eq. 3.18). Its 0.11 px
  floor is that thesis's centroider bias on 10-px spots.
* ``"propagated"`` (the detector's default) -- first-order propagation of a uniform per-pixel
  noise sigma_N through the weighted sum:
  ``var(x_c) = sigma_N**2 * sum_i (x_i - x_c)**2 / (sum_i w_i)**2`` over the pixels with
  positive weight, averaged over x and y, plus :data:`SIGMA_FLOOR_PX` in quadrature. It is the
  background-limited term only (the detector does not know the gain, so signal shot noise is
  left out): right for faint stars, where it matches the scatter of simulated centroids to
  within 10 %, optimistic for bright ones.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal, get_args

import numpy as np
from numpy.typing import NDArray

from ._compiled import region_kernels
from ._label import Regions

PIXEL_VARIANCE = 1.0 / 12.0
"""Variance of a uniform distribution over one pixel, px^2."""

EQ42_FLOOR_PX, EQ42_SCALE_PX, EQ42_EXPONENT = 0.11, 0.5, -1.3
"""Coefficients of Huffman 2006 eq. 4.2."""

UncertaintyModel = Literal["propagated", "eq4.2"]
"""A centroid's error: the method's own (propagated noise or fit covariance) or Huffman 2006 eq. 4.2."""

UNCERTAINTY_MODELS: tuple[str, ...] = get_args(UncertaintyModel)

SIGMA_FLOOR_PX = 0.01
"""Systematic floor of the propagated model, px: the weighted sum's own pixel-phase bias is
below 0.005 px for sampled Gaussians of 0.7 px sd or more; PSF asymmetry, JPEG compression and
pixel response add to it on real images."""


@dataclass(frozen=True)
class SpotMeasurements:
    """Per-spot quantities measured on the full-resolution pixels, all arrays of shape (N,).

    Attributes
    ----------
    x, y : float
        Weighted centroid, our pixel convention (NaN when a spot has no positive pixel).
    flux : float
        Sum of the background-subtracted values over the spot.
    weight : float
        Sum of the clipped weights (flux of the positive pixels).
    peak : float
        Largest background-subtracted value; ``peak_x``, ``peak_y`` (int) locate it.
    area_px : int
        Number of pixels in the spot.
    elongation : float
        sqrt(lambda_max / lambda_min) of the second-moment matrix (>= 1).
    flatness : float
        Fowler 2013 "flatness factor" as a fraction: std of the spot's values / peak.
    spread_px2 : float
        sum_i (x_i - x_c)^2 + (y_i - y_c)^2 over positive pixels, for the propagated sigma.
    size_px : float
        Intensity-weighted RMS radius per axis, sqrt((cxx + cyy) / 2) without the pixel's own
        1/12 px^2: about the PSF's standard deviation (less, when a threshold cut the wings).
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    flux: NDArray[np.float64]
    weight: NDArray[np.float64]
    peak: NDArray[np.float64]
    peak_x: NDArray[np.int64]
    peak_y: NDArray[np.int64]
    area_px: NDArray[np.int64]
    elongation: NDArray[np.float64]
    flatness: NDArray[np.float64]
    spread_px2: NDArray[np.float64]
    size_px: NDArray[np.float64]


def measure_spots(regions: Regions, signal: NDArray[np.float64]) -> SpotMeasurements:
    """Centroid, flux, peak and shape of each region.

    Parameters
    ----------
    regions : Regions
        Full-resolution pixels of N spots.
    signal : ndarray, shape (M,)
        Background-subtracted value of each of those pixels (0 for pixels to ignore).

    Returns
    -------
    SpotMeasurements
    """
    x, y = regions.x.astype(np.float64), regions.y.astype(np.float64)
    signal = np.ascontiguousarray(signal, dtype=np.float64)
    loops = region_kernels()
    m = loops.weighted_moments(regions.starts, x, y, np.maximum(signal, 0.0))
    sums, top = loops.signal_sums(regions.starts, signal)
    cxx, cyy, cxy = m[:, 3] + PIXEL_VARIANCE, m[:, 4] + PIXEL_VARIANCE, m[:, 5]
    area, peak = regions.counts, signal[top]
    return SpotMeasurements(
        x=m[:, 1], y=m[:, 2], flux=sums[:, 0], weight=m[:, 0], peak=peak,
        peak_x=regions.x[top], peak_y=regions.y[top], area_px=area,
        elongation=axis_ratio(cxx, cyy, cxy), flatness=_flatness(sums, area, peak),
        spread_px2=m[:, 6], size_px=np.sqrt(np.maximum(0.5 * (cxx + cyy) - PIXEL_VARIANCE, 0.0)),
    )


def axis_ratio(cxx: NDArray, cyy: NDArray, cxy: NDArray) -> NDArray[np.float64]:
    """Ratio of principal axes of the 2 x 2 moment matrices [[cxx, cxy], [cxy, cyy]]."""
    mean = 0.5 * (cxx + cyy)
    half_diff = np.sqrt(0.25 * (cxx - cyy) ** 2 + cxy**2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt((mean + half_diff) / np.maximum(mean - half_diff, 1e-12))


def _flatness(sums: NDArray, n: NDArray, peak: NDArray) -> NDArray[np.float64]:
    """std of the spot's background-subtracted values divided by its peak (Fowler 2013 FF / 100),
    from the sums of the values and of their squares (N, 2) over the ``n`` (N,) pixels."""
    mean = sums[:, 0] / n
    var = np.maximum(sums[:, 1] / n - mean**2, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(var) / peak


def sigma_eq42(snr_peak: NDArray) -> NDArray[np.float64]:
    """Huffman 2006 eq. 4.2: 1-sigma centroid error in px from the peak-pixel SNR (eq. 3.18)."""
    snr = np.maximum(np.asarray(snr_peak, dtype=np.float64), 1e-3)
    return EQ42_FLOOR_PX + EQ42_SCALE_PX * snr**EQ42_EXPONENT


def sigma_propagated(spots: SpotMeasurements, pixel_noise: NDArray | float) -> NDArray[np.float64]:
    """Background-limited 1-sigma centroid error per axis, px (module docstring)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma = np.asarray(pixel_noise) * np.sqrt(0.5 * spots.spread_px2) / spots.weight
    return np.hypot(sigma, SIGMA_FLOOR_PX)


def centroid_sigma(spots: SpotMeasurements, pixel_noise: NDArray | float, model: str
                   ) -> NDArray[np.float64]:
    """Centroid uncertainty by the named model (``"eq4.2"`` or ``"propagated"``), px."""
    if model == "propagated":
        return sigma_propagated(spots, pixel_noise)
    with np.errstate(invalid="ignore", divide="ignore"):
        return sigma_eq42(spots.peak / np.asarray(pixel_noise))


def take_spots(spots: SpotMeasurements, index: NDArray) -> SpotMeasurements:
    """A subset or reordering of the spots, by index array or boolean mask."""
    return SpotMeasurements(**{f.name: getattr(spots, f.name)[index] for f in fields(spots)})
