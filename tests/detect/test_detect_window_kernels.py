"""The windowed centroider's compiled loops (:mod:`startrack.detect._window_kernels`), the
iteration and the uncertainty, against the numpy computations they replace."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import erf

from startrack.detect import _centroid_windowed as cw
from startrack.detect._windows import Windows, fast_median, fast_quantile, separable_moments


def _centred(axes, size, cx, cy):
    """Per-axis offsets of the windows' pixels from (cx, cy) and their Gaussian weights, (N, S)."""
    k = np.arange(size, dtype=np.float64)
    dx, dy = axes.x0[:, None] + k - cx[:, None], axes.y0[:, None] + k - cy[:, None]
    inv = axes.inv[:, None]
    return dx, dy, np.exp(dx * dx * inv), np.exp(dy * dy * inv)


def _numpy_iterate(axes, signal, cx, cy):
    """The iteration in numpy: all windows step together until every step is below tolerance."""
    total = np.zeros(len(cx))
    for _ in range(cw.MAX_ITERATIONS):
        dx, dy, wx, wy = _centred(axes, signal.shape[-1], cx, cy)
        m = separable_moments(signal, wx, dx, wy, dy)
        total = m[:, 0, 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            first = np.stack([m[:, 0, 1], m[:, 1, 0]]) / total
            v = (m[:, 0, 2] + m[:, 2, 0]) / (2.0 * total)
            gain = np.clip(1.0 / (1.0 + 2.0 * v * axes.inv), 1.0, 4.0)
        step = first * np.where(np.isfinite(gain), gain, 2.0)
        step[~np.isfinite(step)] = 0.0
        np.clip(step, -cw.MAX_STEP_PX, cw.MAX_STEP_PX, out=step)
        cx += step[0]
        cy += step[1]
        if np.all(np.abs(step) < cw.TOLERANCE_PX):
            break
    return cx, cy, total


def _numpy_sigma(axes, signal, valid, cx, cy, sp2, noise, gain):
    """The uncertainty in numpy: a pixel-integrated Gaussian of variance ``sp2`` fitted (with a
    constant) by least squares, and the larger of the modelled and the empirical numerator."""
    dx, dy, wx, wy = _centred(axes, signal.shape[-1], cx, cy)
    m = separable_moments(signal, wx, dx, wy, dy)
    d = m[:, 0, 0] * axes.sw2 / (sp2 + 1.0 / 12 + axes.sw2)
    with np.errstate(invalid="ignore", divide="ignore"):
        offsets = np.stack([dy, dx])
        edges = np.concatenate([offsets - 0.5, offsets[:, :, -1:] + 0.5], axis=2) / (np.sqrt(2.0 * sp2))[:, None]
        share = 0.5 * np.diff(erf(edges), axis=2)
        shape = share[0][:, :, None] * share[1][:, None, :] * valid
        n, sx, sy, sxx, sxy = np.stack([valid, shape, signal, shape * shape, shape * signal]).sum(axis=(2, 3))
        a = (n * sxy - sx * sy) / (n * sxx - sx * sx)
        b = (sy - a * sx) / n
        residual = (signal - a[:, None, None] * shape - b[:, None, None]) * valid
        var = (noise[:, None, None] ** 2 + (np.maximum(signal, 0.0) / gain if gain else 0.0)) * valid
        lever = separable_moments(np.stack([var, residual * residual]), wx**2, dx, wy**2, dy)
        num = 0.5 * np.maximum(*(lever[:, :, 0, 2] + lever[:, :, 2, 0]))
        return np.where(d > 0, np.sqrt(num) / d, np.nan)


def _stars(n: int, half: int, seed: int) -> tuple[Windows, np.ndarray, np.ndarray, np.ndarray]:
    """n noisy Gaussian stars in windows (a few empty, negative or NaN-holed), their start
    positions and window widths."""
    rng = np.random.default_rng(seed)
    size = 2 * half + 1
    x0, y0 = rng.integers(-3, 500, n), rng.integers(-3, 500, n)
    tx, ty = x0 + half + rng.uniform(-2, 2, n), y0 + half + rng.uniform(-2, 2, n)
    sigma = rng.uniform(0.7, 3.0, n)
    k = np.arange(size)
    gx = np.exp(-((x0[:, None] + k - tx[:, None]) ** 2) / (2 * sigma[:, None] ** 2))
    gy = np.exp(-((y0[:, None] + k - ty[:, None]) ** 2) / (2 * sigma[:, None] ** 2))
    values = rng.uniform(5, 500, n)[:, None, None] * gy[:, :, None] * gx[:, None, :]
    values += rng.normal(0, 3.0, values.shape)
    values[0] = 0.0  # no signal: steps are NaN, set to 0
    values[1] = -values[1]  # negative sum: gain out of range
    values[2, :2] = np.nan
    start_x, start_y = x0 + half + rng.uniform(-1, 1, n), y0 + half + rng.uniform(-1, 1, n)
    return Windows(values, x0, y0), start_x, start_y, sigma


@pytest.mark.parametrize(("n", "half", "seed"), [(40, 4, 0), (25, 6, 1), (3, 1, 2)])
def test_compiled_iteration_gives_numpys_centroids(n, half, seed):
    windows, sx, sy, sw = _stars(n, half, seed)
    signal = np.nan_to_num(windows.values)
    axes = cw._Axes.of(windows, sw)
    x, y, total = cw._iterate(axes, signal, sx.copy(), sy.copy())
    ex, ey, etotal = _numpy_iterate(axes, signal, sx.copy(), sy.copy())
    np.testing.assert_allclose(x, ex, rtol=0, atol=1e-10)  # px
    np.testing.assert_allclose(y, ey, rtol=0, atol=1e-10)  # px
    np.testing.assert_allclose(total, etotal, rtol=1e-12, atol=1e-9)  # image units
    assert np.abs(x - sx).max() > 0.01  # the windows did move


@pytest.mark.parametrize(("n", "half", "seed", "gain"), [(40, 4, 0, None), (25, 6, 1, 2.5), (3, 1, 2, None)])
def test_compiled_uncertainty_gives_numpys(n, half, seed, gain):
    windows, sx, sy, sw = _stars(n, half, seed)
    valid = np.isfinite(windows.values)
    signal = np.nan_to_num(windows.values)
    axes = cw._Axes.of(windows, sw)
    x, y, _ = cw._iterate(axes, signal, sx.copy(), sy.copy())
    noise = np.random.default_rng(seed).uniform(1.0, 5.0, n)
    psf = sw * np.random.default_rng(seed + 1).uniform(0.8, 1.2, n)
    got = cw._sigma(axes, signal, valid, x, y, psf, noise, gain)
    expected = _numpy_sigma(axes, signal, valid, x, y, psf**2, noise, gain)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=0)  # px
    assert np.isnan(got[0]) and np.isfinite(got[3:]).all()  # the empty window has no positive sum


def test_frame_width_is_the_median_of_the_windows():
    """Without a PSF width, every window takes the median of the widths their second moments give."""
    windows, sx, sy, sw = _stars(30, 5, 3)
    sw = np.full(30, 1.5)
    valid = np.isfinite(windows.values)
    signal = np.nan_to_num(windows.values)
    axes = cw._Axes.of(windows, sw)
    x, y, _ = cw._iterate(axes, signal, sx.copy(), sy.copy())
    noise = np.full(30, 3.0)
    dx, dy, wx, wy = _centred(axes, signal.shape[-1], x, y)
    m = separable_moments(signal, wx, dx, wy, dy)
    with np.errstate(invalid="ignore", divide="ignore"):
        v = 0.5 * (m[:, 0, 2] + m[:, 2, 0]) / m[:, 0, 0]
        sp2 = v * axes.sw2 / (axes.sw2 - v) - 1.0 / 12
    sp2 = np.clip(np.where(np.isfinite(sp2) & (v < axes.sw2), sp2, 4.0 * axes.sw2), 0.25 * axes.sw2, 4.0 * axes.sw2)
    expected = _numpy_sigma(axes, signal, valid, x, y, np.full(30, np.median(sp2)), noise, None)
    np.testing.assert_allclose(cw._sigma(axes, signal, valid, x, y, None, noise, None), expected,
                               rtol=1e-9, atol=0)  # px


def test_no_windows():
    windows = Windows(np.zeros((0, 5, 5)), np.zeros(0, np.int64), np.zeros(0, np.int64))
    axes = cw._Axes.of(windows, np.zeros(0))
    x, y, total = cw._iterate(axes, windows.values, np.zeros(0), np.zeros(0))
    assert x.size == y.size == total.size == 0
    assert cw._sigma(axes, windows.values, windows.values > 0, x, y, None, np.zeros(0), None).size == 0


def test_fast_quantile_and_median_are_numpys():
    rng = np.random.default_rng(5)
    for _ in range(300):
        values = np.round(rng.normal(2.0, 1.0, int(rng.integers(1, 60))), int(rng.integers(0, 3)))  # ties
        for q in (0.0, 0.1, 0.3, 0.5, 0.9, 1.0, float(rng.uniform())):
            assert fast_quantile(values, q) == float(np.quantile(values, q))
        assert float(fast_median(values)) == float(np.median(values))
