"""The windowed centroider's compiled iteration (:mod:`startrack.detect._window_kernels`) against
the numpy computation it replaces."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect import _centroid_windowed as cw
from startrack.detect._windows import Windows, fast_median, fast_quantile, separable_moments


def _numpy_iterate(axes, signal, cx, cy):
    """The iteration in numpy: all windows step together until every step is below tolerance."""
    total = np.zeros(len(cx))
    for _ in range(cw.MAX_ITERATIONS):
        at = axes.at(cx, cy)
        m = separable_moments(signal, at.wx, at.dx, at.wy, at.dy)
        total = m[:, 0, 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            first = np.stack([m[:, 0, 1], m[:, 1, 0]]) / total
            v = (m[:, 0, 2] + m[:, 2, 0]) / (2.0 * total)
            gain = np.clip(1.0 / (1.0 + 2.0 * v * axes.inv[:, 0]), 1.0, 4.0)
        step = first * np.where(np.isfinite(gain), gain, 2.0)
        step[~np.isfinite(step)] = 0.0
        np.clip(step, -cw.MAX_STEP_PX, cw.MAX_STEP_PX, out=step)
        cx += step[0]
        cy += step[1]
        if np.all(np.abs(step) < cw.TOLERANCE_PX):
            break
    return cx, cy, total


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


def test_no_windows():
    windows = Windows(np.zeros((0, 5, 5)), np.zeros(0, np.int64), np.zeros(0, np.int64))
    axes = cw._Axes.of(windows, np.zeros(0))
    x, y, total = cw._iterate(axes, windows.values, np.zeros(0), np.zeros(0))
    assert x.size == y.size == total.size == 0


def test_fast_quantile_and_median_are_numpys():
    rng = np.random.default_rng(5)
    for _ in range(300):
        values = np.round(rng.normal(2.0, 1.0, int(rng.integers(1, 60))), int(rng.integers(0, 3)))  # ties
        for q in (0.0, 0.1, 0.3, 0.5, 0.9, 1.0, float(rng.uniform())):
            assert fast_quantile(values, q) == float(np.quantile(values, q))
        assert float(fast_median(values)) == float(np.median(values))
