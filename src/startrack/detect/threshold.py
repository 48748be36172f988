"""k-sigma thresholding (seed 000 §4.1, notes ``seed-000.md`` §1.5).

A pixel is a candidate star pixel when its value exceeds the background by more than k times
the noise. The detector thresholds the detection image (see :mod:`.smooth`) in units of that
image's own noise, so k keeps its usual meaning (about 3e-7 false pixels per pixel at 5 sigma
for Gaussian noise) whatever the binning and smoothing.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .background import BackgroundModel


def significance(image: NDArray[np.float32], model: BackgroundModel, binning: int = 1
                 ) -> NDArray[np.float32]:
    """(image - level) / noise, pixel by pixel, in units of the noise.

    Parameters
    ----------
    image : ndarray of float32, shape (h, w)
        The detection image.
    model : BackgroundModel
        Background of ``image``, with tile centres in full-resolution pixels.
    binning : int
        Binning of ``image`` relative to full resolution; its pixel (i, j) is centred on
        full-resolution row i * binning + (binning - 1) / 2 (and likewise for columns).

    Returns
    -------
    ndarray of float32, shape (h, w)
    """
    h, w = image.shape
    centre = (binning - 1) / 2
    ys, xs = centre + binning * np.arange(h), centre + binning * np.arange(w)
    if model.level_map is not None and model.level_map.shape == image.shape:
        level, noise = model.level_map, model.noise_map(ys, xs)
    else:
        level, noise = model.maps(ys, xs)
    snr = image - np.float32(level) if np.isscalar(level) else image - level
    if np.isscalar(noise):
        snr *= np.float32(1.0 / noise)
    else:
        snr /= noise
    return snr


def threshold_mask(snr: NDArray, k_sigma: float) -> NDArray[np.bool_]:
    """Pixels more than ``k_sigma`` noise units above the background (bool, same shape)."""
    return snr > k_sigma
