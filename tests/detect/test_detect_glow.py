"""Stars in the Moon's glow are detected: the clutter ratio is measured on the residual from the
interpolated background level too, as the noise is, and the smaller ratio counts, so that the
glow's gradient across a tile does not count as clutter (lit leaves and roof texture, which vary
within a tile, still do).

Before, a tile's lower-half width was that of its raw values: where the glow fell by tens of
its noise across a 32 px tile, the tiles looked 3-10 times as cluttered as the clean sky and
every star in them was refused (``max_clutter`` 2.5). A glow bright enough to raise the photon
noise 2.5 times over the sky's still counts as clutter: the ratio compares widths, whatever
makes them.
"""

from __future__ import annotations

import numpy as np

from startrack.detect import StarDetector
from startrack.simulate import render_gaussian_psf

SHAPE = (384, 512)
PSF_SIGMA_PX = 1.4


def _glow_frame(amplitude: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """uint16 frame: 25 stars of peak 400-900 DN on a 200 DN sky with shot noise, a glow of
    ``amplitude`` DN at the top-left corner falling with the cube of the distance; the stars'
    x, y (px)."""
    rng = np.random.default_rng(12)
    gy, gx = np.mgrid[40:384:80, 50:512:110]
    x, y = gx.ravel() + rng.uniform(-10, 10, gx.size), gy.ravel() + rng.uniform(-10, 10, gy.size)
    peak = rng.uniform(400.0, 900.0, x.size)
    yy, xx = np.mgrid[0:SHAPE[0], 0:SHAPE[1]]
    glow = amplitude * (150.0 / (np.hypot(xx + 60.0, yy + 60.0) + 150.0)) ** 3
    mean = 200.0 + glow + render_gaussian_psf(SHAPE, x, y, peak * 2 * np.pi * PSF_SIGMA_PX**2, PSF_SIGMA_PX)
    return rng.poisson(mean).astype(np.uint16), x, y


def _found(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    det = StarDetector().detect(image)
    return np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None]).min(axis=1) < 1.0  # px


def test_stars_in_a_glow_are_found():
    # about 500 DN over the nearest star, falling by up to 160 DN (11 times the sky's noise)
    # across a 32 px tile; before, 5 of the 25 stars were refused as in clutter
    image, x, y = _glow_frame(4000.0)
    found = _found(image, x, y)
    assert found.all(), f"missed stars at {np.c_[x, y][~found].round(1).tolist()}"


def test_without_the_glow_the_same_stars_are_found():
    image, x, y = _glow_frame(0.0)
    assert _found(image, x, y).all()
