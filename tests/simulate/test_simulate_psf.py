"""PSF rendering: pixel integration, flux and centroid, edge clipping, linearity."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate
from scipy.stats import norm

from startrack.errors import InvalidInputError
from startrack.simulate import render_gaussian_psf
from startrack.units import PIXEL


def centroid(image: np.ndarray) -> tuple[float, float]:
    """Intensity-weighted centroid (x, y) in our pixel convention."""
    rows, cols = np.indices(image.shape)
    total = image.sum()
    return float((cols * image).sum() / total), float((rows * image).sum() / total)


def test_pixel_values_match_numerical_integration_of_the_gaussian():
    x, y, sigma = 10.3, 8.8, 1.2
    image = render_gaussian_psf((20, 24), [x], [y], [1.0], sigma)

    def density(yy, xx):
        return np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * sigma**2)) / (2 * np.pi * sigma**2)

    for px, py in [(10, 9), (11, 8), (8, 10), (13, 6)]:
        ref, _ = integrate.dblquad(density, px - 0.5, px + 0.5, py - 0.5, py + 0.5, epsabs=1e-13)
        assert image[py, px] == pytest.approx(ref, rel=1e-8, abs=1e-14)


@pytest.mark.parametrize("sigma", [0.8, 2.5])
def test_flux_is_conserved_and_centroid_is_the_true_position(sigma):
    rng = np.random.default_rng(5)
    for x, y in rng.uniform(30, 34, size=(5, 2)):
        image = render_gaussian_psf((64, 64), [x], [y], [5000.0], sigma)
        assert image.sum() == pytest.approx(5000.0, rel=1e-6)
        cx, cy = centroid(image)
        assert abs(cx - x) < 0.01 * PIXEL and abs(cy - y) < 0.01 * PIXEL


def test_star_partly_off_the_edge_loses_exactly_the_light_outside():
    x, y, sigma, flux = -1.3, 39.6, 2.0, 1000.0
    image = render_gaussian_psf((50, 60), [x], [y], [flux], sigma)
    fraction_x = 1.0 - norm.cdf(-0.5, loc=x, scale=sigma)       # light right of the left edge
    fraction_y = norm.cdf(49.5, loc=y, scale=sigma) - norm.cdf(-0.5, loc=y, scale=sigma)
    assert image.sum() == pytest.approx(flux * fraction_x * fraction_y, rel=1e-6)


def test_corner_and_far_away_stars_render_without_error():
    image = render_gaussian_psf((30, 40), [39.9, -500.0, 1e6], [29.7, 10.0, -1e6],
                                [100.0, 100.0, 100.0], 1.5)
    assert 0.0 < image.sum() < 100.0
    assert image[29, 39] == image.max()


def test_rendering_is_linear_in_the_stars():
    x, y, f = [5.2, 30.7, 31.0], [7.9, 12.1, 14.4], [1.0, 2.0, 3.5]
    together = render_gaussian_psf((25, 40), x, y, f, 1.7)
    apart = sum(render_gaussian_psf((25, 40), [xi], [yi], [fi], 1.7)
                for xi, yi, fi in zip(x, y, f, strict=True))
    np.testing.assert_allclose(together, apart, rtol=1e-12, atol=1e-15)


def test_per_star_sigma_and_out_accumulate():
    out = np.ones((40, 40))
    result = render_gaussian_psf((0, 0), [10.0, 22.0], [10.0, 22.0], [1.0, 1.0], [1.0, 3.0],
                                 out=out)
    assert result is out
    narrow = out[10, 10] - 1.0
    wide = out[22, 22] - 1.0
    assert narrow > 5 * wide  # peak scales as 1 / sigma^2
    assert out.sum() - 40 * 40 == pytest.approx(2.0, rel=1e-6)


def test_no_stars_gives_an_empty_image():
    assert not render_gaussian_psf((8, 9), [], [], [], 1.0).any()


@pytest.mark.parametrize("kwargs", [
    {"x": [1.0], "y": [1.0, 2.0], "flux": [1.0], "sigma_px": 1.0},
    {"x": [1.0], "y": [1.0], "flux": [1.0], "sigma_px": 0.0},
    {"x": [np.nan], "y": [1.0], "flux": [1.0], "sigma_px": 1.0},
    {"x": [1.0], "y": [1.0], "flux": [1.0], "sigma_px": 1.0, "out": np.zeros((4, 4), int)},
])
def test_misuse_raises(kwargs):
    with pytest.raises(InvalidInputError):
        render_gaussian_psf((10, 10), **kwargs)
