"""The fast paths of the predictive pass and of the windowed centroider agree with the direct
(slower) computations: the lean spot measurement of whole windows with ``measure_spots`` on the
pixel lists, the separable moments and uncertainty sums with (N, S, S) sums, the partition
median with ``np.median``."""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest
from scipy.special import erf
from star_render import random_positions, render_stars

from startrack.detect import StarDetector
from startrack.detect._centroid import measure_spots
from startrack.detect._centroid_windowed import pixel_variance, windowed_centroid
from startrack.detect._predictive import _pixels, _window_regions, cut_windows, ring_statistics, window_spots
from startrack.detect._windows import fast_median, separable_moments
from startrack.units import PIXEL

SHAPE = (160, 160)


@pytest.fixture(scope="module")
def windows_case():
    """Integer-valued image with a tie for a peak, 12 stars, windows at the border and with NaN
    pixels, predictions off by up to 1.5 px."""
    rng = np.random.default_rng(21)
    x, y = random_positions(12, SHAPE, margin=3, min_sep=14, rng=rng)
    flux = np.geomspace(800.0, 3e4, 12)
    image = np.rint(render_stars(SHAPE, x, y, flux, sigma_px=1.4, background=90.0, read_noise=5.0,
                                 rng=rng, shot_noise=True))
    image[int(y[3]) - 1, :] = np.nan
    row, col = int(round(y[5])), int(round(x[5]))
    image[row, col: col + 2] = image[row, col] + 3000.0  # a tie for the peak
    px, py = x + rng.uniform(-1.5, 1.5, x.size), y + rng.uniform(-1.5, 1.5, y.size)
    windows = cut_windows(image, px, py, 6, None)
    level, noise = ring_statistics(windows)
    signal = windows.values - level[:, None, None]
    return image, x, y, px, py, windows, level, noise, signal


def test_lean_window_spots_equal_measure_spots_on_pixel_lists(windows_case):
    *_, windows, _, noise, signal = windows_case
    threshold = 3.0 * noise
    regions = _window_regions(signal, windows, threshold)
    assert np.all(regions.counts > 0)
    general = measure_spots(regions, _pixels(signal, windows, regions))
    lean = window_spots(signal, windows, threshold)
    for f in fields(general):
        np.testing.assert_allclose(getattr(lean, f.name), getattr(general, f.name), rtol=1e-12,
                                   atol=1e-9, err_msg=f.name)


def test_lean_predictive_pass_gives_the_general_paths_centroids(windows_case):
    image, x, y, px, py, windows, level, noise, signal = windows_case
    result = StarDetector(psf_sigma_px=1.4).measure_windows(image, px, py, 6)
    found = result.window_index
    assert np.array_equal(np.sort(found), np.arange(len(x)))
    regions = _window_regions(signal, windows, 3.0 * noise)
    spots = measure_spots(regions, _pixels(signal, windows, regions))
    general = windowed_centroid(windows, level, noise, spots.x, spots.y, 1.4)
    det = result.detections
    np.testing.assert_allclose(det.x, general.x[found], atol=1e-9 * PIXEL)
    np.testing.assert_allclose(det.y, general.y[found], atol=1e-9 * PIXEL)
    np.testing.assert_allclose(det.sigma_px, general.sigma_px[found], rtol=1e-9)
    np.testing.assert_allclose(det.flux, spots.flux[found], rtol=1e-12)
    real = found != 5  # star 5 has an added pixel pair (the peak tie)
    np.testing.assert_allclose(det.x[real], x[found[real]], atol=0.15 * PIXEL)


def test_separable_moments_are_the_direct_sums():
    rng = np.random.default_rng(22)
    q = rng.normal(size=(2, 4, 7, 7))
    wx, dx, wy, dy = rng.uniform(0.1, 1.0, (4, 4, 7))
    m = separable_moments(q, wx, dx, wy, dy)
    for a in range(3):
        for b in range(3):
            direct = np.einsum("kji,j,i->k", q[:, 1], wy[1] * dy[1] ** a, wx[1] * dx[1] ** b)
            np.testing.assert_allclose(m[:, 1, a, b], direct, rtol=1e-12)


@pytest.mark.parametrize("n", [1, 2, 47, 48])
def test_fast_median_is_numpys_median(n):
    values = np.random.default_rng(n).normal(size=(5, n))
    values[0, : n // 2] = 1.0  # ties
    assert np.array_equal(fast_median(values), np.median(values, axis=-1))
    assert fast_median(values[2]) == np.median(values[2])


def _direct_sigma(windows, level, noise, cx, cy, sw, sp, gain):
    """The module docstring's uncertainty with full (N, S, S) weights and residuals."""
    k = np.arange(windows.values.shape[1])
    xs = (windows.x0[:, None] + k)[:, None, :] - cx[:, None, None]
    ys = (windows.y0[:, None] + k)[:, :, None] - cy[:, None, None]
    signal = windows.values - level[:, None, None]
    valid = np.isfinite(signal)
    signal = np.where(valid, signal, 0.0)
    w = np.exp(-(xs**2 + ys**2) / (2 * sw**2)) * valid
    d = (w * signal).sum(axis=(1, 2)) * sw**2 / (sp**2 + 1 / 12 + sw**2)
    g = 0.5 * (erf((xs + 0.5) / (np.sqrt(2) * sp)) - erf((xs - 0.5) / (np.sqrt(2) * sp)))
    g = g * 0.5 * (erf((ys + 0.5) / (np.sqrt(2) * sp)) - erf((ys - 0.5) / (np.sqrt(2) * sp))) * valid
    design = np.stack([g, valid * 1.0], axis=-1).reshape(len(cx), -1, 2)
    residual = np.empty_like(signal)
    for n in range(len(cx)):
        coef = np.linalg.lstsq(design[n], signal[n].ravel(), rcond=None)[0]
        residual[n] = (signal[n] - (design[n] @ coef).reshape(signal[n].shape)) * valid[n]
    lever = w * w * (xs**2 + ys**2)
    model = (lever * pixel_variance(signal, noise, gain)).sum(axis=(1, 2))
    num = 0.5 * np.maximum(model, (lever * residual**2).sum(axis=(1, 2)))
    return np.sqrt(num) / d


@pytest.mark.parametrize("gain", [None, 0.5])
def test_separable_uncertainty_is_the_direct_formula(windows_case, gain):
    *_, windows, level, noise, signal = windows_case
    spots = window_spots(signal, windows, 3.0 * noise)
    result = windowed_centroid(windows, level, noise, spots.x, spots.y, 1.4, psf_sigma_px=np.full(12, 1.4),
                               gain_e_per_adu=gain)
    direct = _direct_sigma(windows, level, noise, result.x, result.y, 1.4, 1.4, gain)
    np.testing.assert_allclose(result.sigma_px, direct, rtol=1e-9)
