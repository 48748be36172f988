"""Centroids from the pixels of a spot: peak, area, intensity-weighted (Fowler 2013 §II.C,
its centroid methods 1-3; Huffman 2006 §4.2.2 eq. 4.1).

* ``"peak"`` -- the centre of the brightest pixel; error about 1/sqrt(12) px per axis when the
  star image is smaller than a pixel, more otherwise.
* ``"area"`` -- the unweighted mean of the spot's pixel centres (Fowler 2013 eq. 3.2), for binary
  images or unreliable intensities.
* ``"weighted"`` -- Huffman 2006's weighted sum with the background subtracted,
  ``sum w_i x_i / sum w_i`` with ``w_i = max(I_i - B_i, 0)`` (Fowler 2013 eq. 3.3): the detector's
  default, measured in :func:`startrack.detect._centroid.measure_spots`.
* ``"weighted-raw"`` -- the same with the raw pixel values as weights (no background
  subtraction): every pixel's background pulls the centroid towards the centre of the spot's
  pixel set, which is why Huffman 2006 subtracts a dark frame first.

Each returns :class:`startrack.detect._windows.Centroids`. Uncertainties: ``weighted`` and
``weighted-raw`` propagate a uniform pixel noise through the sum (``centroid.sigma_propagated``);
``peak`` gives sqrt(1/12) px; ``area`` gives Huffman 2006's eq. 4.2 curve (the membership of the
spot's edge pixels, not the pixel noise, moves it).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._centroid import SIGMA_FLOOR_PX, SpotMeasurements, sigma_eq42, sigma_propagated
from ._label import Regions
from ._windows import Centroids

PEAK_SIGMA_PX = float(np.sqrt(1.0 / 12.0))


def _result(x, y, sigma, n: int) -> Centroids:
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    nan = np.full(n, np.nan)
    return Centroids(x=x, y=y, flux=nan, sigma_px=np.broadcast_to(sigma, (n,)).astype(np.float64),
                     psf_sigma_px=nan.copy(), ok=np.isfinite(x) & np.isfinite(y))


def peak_centroid(spots: SpotMeasurements) -> Centroids:
    """The brightest pixel's centre."""
    return _result(spots.peak_x, spots.peak_y, PEAK_SIGMA_PX, len(spots.x))


def area_centroid(regions: Regions, spots: SpotMeasurements, pixel_noise: NDArray) -> Centroids:
    """The unweighted mean of the spot's pixel centres (Fowler 2013 eq. 3.2)."""
    n = regions.counts
    x = regions.sum(regions.x.astype(np.float64)) / n
    y = regions.sum(regions.y.astype(np.float64)) / n
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma = sigma_eq42(spots.peak / pixel_noise)
    return _result(x, y, sigma, len(n))


def weighted_centroid(spots: SpotMeasurements, pixel_noise: NDArray) -> Centroids:
    """The background-subtracted weighted sum (already measured with the spot)."""
    return _result(spots.x, spots.y, sigma_propagated(spots, pixel_noise), len(spots.x))


def weighted_raw_centroid(regions: Regions, raw: NDArray, pixel_noise: NDArray) -> Centroids:
    """The weighted sum with the raw pixel values ``raw`` (shape (M,)) as weights."""
    w = np.where(np.isfinite(raw), np.maximum(raw, 0.0), 0.0)
    x, y = regions.x.astype(np.float64), regions.y.astype(np.float64)
    total = regions.sum(w)
    with np.errstate(invalid="ignore", divide="ignore"):
        xc, yc = regions.sum(w * x) / total, regions.sum(w * y) / total
        dx, dy = x - xc[regions.index], y - yc[regions.index]
        spread = regions.sum(np.where(w > 0, dx * dx + dy * dy, 0.0))
        sigma = np.asarray(pixel_noise) * np.sqrt(0.5 * spread) / total
    return _result(xc, yc, np.hypot(sigma, SIGMA_FLOOR_PX), len(total))
