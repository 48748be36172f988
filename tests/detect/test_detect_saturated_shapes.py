"""Saturated spots that are not stars: the strokes of a caption, a watermark or a logo.

Their flat cores skip the size test (a clipped star's core is wider than the PSF too), so
before, only their elongation counted, against the frame's median elongation, which their own
pieces set when they outnumber the stars. Now a saturated spot's core must fill the ellipse of
its second moments (a clipped star's core is a disc), and the frame's reference size and
elongation come from its unsaturated spots when there are enough.
"""

from __future__ import annotations

import numpy as np

from startrack.detect import StarDetector
from startrack.detect._point_source import CoreShape, point_quality
from startrack.simulate import render_gaussian_psf

SHAPE = (300, 400)
PSF_SIGMA_PX = 1.3


def _frame() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """uint8 frame: 16 stars on a noisy sky, 4 of them saturated (peaks 5-20 times the clip), a
    saturated ring (a letter 'O', 16 px across) and a saturated hook (a 'J'); the stars' x, y
    (px) and which are saturated."""
    rng = np.random.default_rng(5)
    gy, gx = np.mgrid[30:210:50, 40:380:90]
    x, y = gx.ravel() + rng.uniform(-8, 8, gx.size), gy.ravel() + rng.uniform(-8, 8, gy.size)
    peak = rng.uniform(40.0, 120.0, x.size)
    saturated = np.zeros(x.size, dtype=bool)
    saturated[[1, 6, 9, 14]] = True
    peak[saturated] = rng.uniform(1200.0, 5000.0, 4)
    mean = render_gaussian_psf(SHAPE, x, y, peak * 2 * np.pi * PSF_SIGMA_PX**2, PSF_SIGMA_PX) + 20.0
    yy, xx = np.mgrid[0:SHAPE[0], 0:SHAPE[1]]
    ring = np.hypot(xx - 100.0, yy - 262.0)
    mean[(ring >= 5.5) & (ring <= 8.0)] = 255.0
    mean[250:274, 236:239] = 255.0  # the J's stem
    mean[271:274, 222:239] = 255.0  # its foot
    mean[265:274, 222:225] = 255.0  # and its turn up
    image = np.clip(np.rint(mean + rng.normal(0, 2.0, SHAPE)), 0, 255).astype(np.uint8)
    return image, x, y, saturated


def test_saturated_strokes_are_not_point_sources_and_saturated_stars_are():
    image, x, y, saturated = _frame()
    found = StarDetector().detect(image)
    star = np.hypot(x[:, None] - found.x[None], y[:, None] - found.y[None]).min(axis=0) < 1.0  # px
    assert star.sum() == x.size
    is_star_saturated = np.zeros(len(found), dtype=bool)
    for k in np.flatnonzero(saturated):
        is_star_saturated |= np.hypot(found.x - x[k], found.y - y[k]) < 1.0  # px
    assert is_star_saturated.sum() == 4
    assert found.is_point_source[star].all()
    overlay = found.y > 245  # px: the ring and the hook, whatever pieces they break into
    assert overlay.any()
    assert not found.is_point_source[overlay].any()


def test_the_reference_elongation_comes_from_unsaturated_spots():
    """Ten saturated bars (elongation 3, cores that fill their ellipse) among six round stars:
    the bars set the median elongation of all sixteen, not the stars'."""
    n_bars, n_stars = 10, 6
    saturated = np.r_[np.ones(n_bars, bool), np.zeros(n_stars, bool)]
    shape = CoreShape(size=np.r_[np.full(n_bars, 4.0), np.full(n_stars, 1.2)],
                      elongation=np.r_[np.full(n_bars, 3.0), np.full(n_stars, 1.1)], fill=np.full(16, 0.95))
    quality = point_quality(shape, np.full(16, 50.0), saturated)
    np.testing.assert_array_equal(quality[saturated], 0.0)
    np.testing.assert_array_equal(quality[~saturated], 1.0)


def test_a_saturated_core_that_does_not_fill_its_ellipse_is_not_a_point_source():
    fill = np.array([0.98, 0.8, 0.75, 0.675, 0.6, 0.3])
    shape = CoreShape(size=np.full(6, 3.0), elongation=np.ones(6), fill=fill)
    quality = point_quality(shape, np.full(6, 50.0), np.ones(6, bool))
    np.testing.assert_allclose(quality, [1.0, 1.0, 1.0, 0.5, 0.0, 0.0], atol=1e-12)
    unsaturated = point_quality(CoreShape(np.full(6, 1.2), np.ones(6), fill), np.full(6, 50.0), np.zeros(6, bool))
    np.testing.assert_array_equal(unsaturated, 1.0)  # the fill counts for clipped cores only
