"""The windowed centroider's PSF width comes from the unsaturated spots.

A saturated overlay (a timestamp, a watermark) or the Moon's limb breaks into spots brighter
than the stars, with flat clipped cores several pixels wide. Before, the width was the median
size of the brighter half of all spots: 6-8 px against the stars' 1.2 px on the openstartracker
frames with a watermark, the windows grew to their 16 px limit and the stars' centroids were
pulled by several pixels.
"""

from __future__ import annotations

import numpy as np

from startrack.detect import StarDetector
from startrack.simulate import render_gaussian_psf

SHAPE = (300, 400)
PSF_SIGMA_PX = 1.3


def _frame(with_overlay: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """uint8 frame of 16 unsaturated stars on a noisy sky, and with ``with_overlay`` 24 saturated
    glyph-like bars (4 x 9 px) along the bottom; the stars' x, y (px)."""
    rng = np.random.default_rng(7)
    gy, gx = np.mgrid[30:210:50, 40:380:90]
    x, y = gx.ravel() + rng.uniform(-8, 8, gx.size), gy.ravel() + rng.uniform(-8, 8, gy.size)
    peak = rng.uniform(40.0, 120.0, x.size)
    mean = render_gaussian_psf(SHAPE, x, y, peak * 2 * np.pi * PSF_SIGMA_PX**2, PSF_SIGMA_PX) + 20.0
    if with_overlay:
        for k in range(24):
            mean[260:269, 20 + 15 * k: 24 + 15 * k] = 255.0
    image = np.clip(np.rint(mean + rng.normal(0, 2.0, SHAPE)), 0, 255).astype(np.uint8)
    return image, x, y


def test_a_saturated_overlay_does_not_set_the_psf_width():
    plain = StarDetector().detect_details(_frame(False)[0])
    image, x, y = _frame(True)
    details = StarDetector().detect_details(image)
    found = details.detections
    stars = np.hypot(x[:, None] - found.x[None], y[:, None] - found.y[None]).min(axis=0) < 1.0  # px
    assert stars.sum() == x.size
    width = float(np.median(details.psf_sigma_px[stars]))
    assert abs(width - float(np.median(plain.psf_sigma_px))) < 0.1  # px: the overlay does not move it
    assert abs(width - PSF_SIGMA_PX) < 0.3  # px
