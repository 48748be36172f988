"""A registered or stacked frame with wide black (zero) borders: its stars are still found.

Before, once a quarter or more of the background tiles were of one value, the clean sky's noise
came out 0 and fell back on the whole frame's, borders included: 20-30 times the sky's, and most
stars were lost (roof.jpg with a 35 % margin: 3 detections). Tiles of fill
(:func:`startrack.detect._background.fill_tiles`) now count as tiles without a value, as NaN
borders always did.
"""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect import detect
from startrack.detect._background import tiled_background
from startrack.simulate import render_gaussian_psf

SHAPE = (400, 600)
SKY_DN, NOISE_DN = 30.0, 2.0


def _sky(seed: int = 2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """uint8 frame of 30 stars (peaks 12-150 DN) on a noisy sky; the stars' x, y (px)."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(15, SHAPE[1] - 15, 30), rng.uniform(15, SHAPE[0] - 15, 30)
    peak = np.exp(rng.uniform(np.log(12.0), np.log(150.0), 30))
    mean = render_gaussian_psf(SHAPE, x, y, peak * 2 * np.pi * 1.3**2, 1.3) + SKY_DN
    return np.clip(np.rint(mean + rng.normal(0, NOISE_DN, SHAPE)), 0, 255).astype(np.uint8), x, y


def _framed(image: np.ndarray, margin: int, fill: float) -> np.ndarray:
    out = np.full((image.shape[0] + 2 * margin, image.shape[1] + 2 * margin), fill, np.float32)
    out[margin:-margin, margin:-margin] = image
    return out


@pytest.mark.parametrize("margin_fraction", [0.2, 0.35, 0.5])
def test_stars_inside_a_black_border_are_found(margin_fraction):
    image, x, y = _sky()
    margin = int(margin_fraction * SHAPE[1])
    found = detect(_framed(image, margin, 0.0))
    near = np.hypot(x[:, None] + margin - found.x[None], y[:, None] + margin - found.y[None]) < 1.0  # px
    assert near.any(axis=1).mean() >= 0.8, f"{near.any(axis=1).sum()} of {x.size} stars found"


def test_the_border_does_not_count_in_the_noise():
    image, _, _ = _sky()
    plain = tiled_background(image.astype(np.float32), 16).noise
    framed = tiled_background(_framed(image, int(0.35 * SHAPE[1]), 0.0), 16).noise
    assert framed == pytest.approx(plain, rel=0.25)  # the sky's noise, not the border's step (DN)


def test_a_noise_free_sky_is_not_fill():
    """A noise-free frame's sky is of one value in every tile but those with stars: it is the
    sky, not fill, and the stars are found against it."""
    x, y = np.array([100.0, 300.0, 450.0]), np.array([80.0, 200.0, 300.0])
    image = (render_gaussian_psf(SHAPE, x, y, np.full(3, 3000.0), 1.3) + SKY_DN).astype(np.float32)
    found = detect(image)
    assert len(found) == 3
