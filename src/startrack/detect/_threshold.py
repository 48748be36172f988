"""k-sigma thresholding (Huffman 2006 §4.1).

A pixel is a candidate star pixel when its value exceeds the background by more than k times
the noise. The detector thresholds the detection image (see :mod:`._smooth`) in units of that
image's own noise, so k keeps its usual meaning (about 3e-7 false pixels per pixel at 5 sigma
for Gaussian noise) whatever the binning and smoothing.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._background import BackgroundModel
from ._compiled import kernels
from ._smooth import empty_apart
from ._tile_geometry import strided_weights


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
    centre = (binning - 1) / 2  # of the image's pixel (i, j) in full-resolution pixels: centre + binning * (i, j)
    image = np.asarray(image, dtype=np.float32)
    tiles = model.tiles
    if tiles is None:
        level, inverse = np.full((1, 1), model.level, np.float32), np.full((1, 1), 1.0 / model.noise, np.float32)
        rows_i, rows_f = np.zeros(h, np.int64), np.zeros(h, np.float32)
        cols_i, cols_f = np.zeros(w, np.int64), np.zeros(w, np.float32)
        return kernels().significance(image, level, inverse, rows_i, rows_i, rows_f, cols_i, cols_i, cols_f, 0,
                                      empty_apart(image.shape, image))
    y0, y1, wy = strided_weights(tiles.centres_y, h, binning, centre)
    x0, x1, wx = strided_weights(tiles.centres_x, w, binning, centre)
    level_map = model.level_map
    mapped = level_map is not None and level_map.shape == image.shape
    level = level_map if level_map is not None and mapped else tiles.level.astype(np.float32)
    out = empty_apart(image.shape, image, level)
    return kernels().significance(image, level, tiles.noise.astype(np.float32), y0, y1, wy, x0, x1, wx,
                                  1 if mapped else 2, out)


def threshold_mask(snr: NDArray, k_sigma: float) -> NDArray[np.bool_]:
    """Pixels more than ``k_sigma`` noise units above the background (bool, same shape)."""
    return snr > k_sigma
