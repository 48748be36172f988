"""A dark, smooth foreground (a horizon, trees in silhouette) across the lower part of a photo:
the sky's stars are still found. Before, the clutter filter took the foreground, the quietest
quarter of the tiles, for the clean sky, found the whole sky four to six times as busy, and
rejected every star (0 detections with the foreground over 40 % of the frame)."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect import detect
from startrack.simulate import render_gaussian_psf

SHAPE = (512, 768)
SKY_E, GROUND_E = 400.0, 20.0  # e- per pixel: a glowing sky, a dark ground


def _photo(ground_fraction: float, seed: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A frame of 30 stars in the sky (peak SNR 15-150), the lower ``ground_fraction`` of it
    ground: uint16 image and the stars' x, y (px)."""
    rng = np.random.default_rng(seed)
    horizon = int(SHAPE[0] * (1 - ground_fraction))
    x, y = rng.uniform(20, SHAPE[1] - 20, 30), rng.uniform(20, horizon - 20, 30)
    flux = np.exp(rng.uniform(np.log(2e3), np.log(2e4), 30))  # e-
    mean = render_gaussian_psf(SHAPE, x, y, flux, 1.3) + SKY_E
    mean[horizon:] = GROUND_E
    image = rng.poisson(mean) + rng.normal(0.0, 3.0, SHAPE)
    return np.clip(np.rint(image), 0, 65535).astype(np.uint16), x, y


@pytest.mark.parametrize("ground_fraction", [0.0, 0.4, 0.6])
def test_the_stars_above_a_dark_foreground_are_found(ground_fraction):
    image, x, y = _photo(ground_fraction)
    found = detect(image)
    distance = np.hypot(x[:, None] - found.x[None], y[:, None] - found.y[None])
    near = (distance < 1.0).any(axis=1)  # px
    assert near.mean() >= 0.9, f"{near.sum()} of {x.size} stars found"
    assert (~(distance < 1.0).any(axis=0)).sum() <= 2  # detections that are no star (the horizon's edge)


def test_spots_of_a_lit_textured_foreground_are_still_refused():
    """The check above must not undo the clutter filter where it is needed: lit leaves or a roof
    over two thirds of the frame, hundreds of bright round spots on them, a dozen stars above."""
    from scipy import ndimage

    rng = np.random.default_rng(1)
    horizon = int(SHAPE[0] * 0.35)
    x, y = rng.uniform(20, SHAPE[1] - 20, 12), rng.uniform(20, horizon - 20, 12)
    mean = render_gaussian_psf(SHAPE, x, y, np.exp(rng.uniform(np.log(3e3), np.log(2e4), 12)), 1.3) + SKY_E
    texture = ndimage.gaussian_filter(rng.normal(size=SHAPE), 2.0)
    mean[horizon:] += 150.0 * texture[horizon:] / texture.std() + 300.0  # e-
    bx, by = rng.uniform(10, SHAPE[1] - 10, 600), rng.uniform(horizon + 10, SHAPE[0] - 10, 600)
    mean += render_gaussian_psf(SHAPE, bx, by, np.exp(rng.uniform(np.log(3e4), np.log(2e5), 600)), 1.3)
    image = np.clip(np.rint(rng.poisson(np.clip(mean, 0, None)) + rng.normal(0, 3, SHAPE)), 0, 65535).astype(np.uint16)
    found = detect(image)
    assert (found.y > horizon).sum() <= 2  # spots on the foreground (485 with the filter off)
    assert (np.hypot(x[:, None] - found.x[None], y[:, None] - found.y[None]) < 1.0).any(axis=1).all()  # px
