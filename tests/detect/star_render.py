"""A tiny independent star-field renderer for the detector tests (pixel-integrated Gaussians).

Kept separate from :mod:`startrack.simulate` on purpose: the tests check the detector against
positions that a few lines of ``erf`` put on the pixel grid, in our pixel convention (pixel
(i, j) covers x in [j - 0.5, j + 0.5], y in [i - 0.5, i + 0.5]).
"""

from __future__ import annotations

import numpy as np
from scipy.special import erf


def pixel_fractions(centre: float, sigma_px: float, start: int, stop: int) -> np.ndarray:
    """Fraction of a 1-D Gaussian (mean ``centre``, sd ``sigma_px``) in pixels start..stop-1."""
    edges = np.arange(start, stop + 1) - 0.5
    return 0.5 * np.diff(erf((edges - centre) / (np.sqrt(2.0) * sigma_px)))


def render_stars(shape, x, y, flux, sigma_px=1.5, background=100.0, read_noise=0.0,
                 rng=None, shot_noise=False) -> np.ndarray:
    """Float64 image of Gaussian stars at (x, y) with total ``flux`` each, plus background and
    noise (Gaussian read noise of ``read_noise``, optional Poisson shot noise)."""
    rng = np.random.default_rng(rng)
    h, w = shape
    image = np.full(shape, float(background))
    half = int(np.ceil(6 * sigma_px)) + 1
    for xc, yc, f in zip(np.atleast_1d(x), np.atleast_1d(y), np.atleast_1d(flux), strict=True):
        x0, x1 = max(0, int(xc) - half), min(w, int(xc) + half + 1)
        y0, y1 = max(0, int(yc) - half), min(h, int(yc) + half + 1)
        if x0 >= x1 or y0 >= y1:
            continue
        gx = pixel_fractions(xc, sigma_px, x0, x1)
        gy = pixel_fractions(yc, sigma_px, y0, y1)
        image[y0:y1, x0:x1] += f * np.outer(gy, gx)
    if shot_noise:
        image = rng.poisson(np.maximum(image, 0)).astype(float)
    if read_noise > 0:
        image = image + rng.normal(0.0, read_noise, shape)
    return image


def random_positions(n, shape, margin=20.0, min_sep=15.0, rng=None):
    """``n`` random positions (x, y) at least ``margin`` from the edges and ``min_sep`` apart."""
    rng = np.random.default_rng(rng)
    h, w = shape
    xs, ys = [], []
    while len(xs) < n:
        x, y = rng.uniform(margin, w - 1 - margin), rng.uniform(margin, h - 1 - margin)
        if all((x - a) ** 2 + (y - b) ** 2 >= min_sep**2 for a, b in zip(xs, ys, strict=True)):
            xs.append(x)
            ys.append(y)
    return np.array(xs), np.array(ys)
