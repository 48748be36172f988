"""The compiled loops of the windowed centroider (numba): the fixed-point iteration of
:mod:`._centroid_windowed` over a stack of windows.

Each loop gives the numbers of the numpy expressions it replaces, operation for operation (the
separable moments summed along x first, then along y, as :func:`.frame_kernels.separable_moments`
does), so a centroid does not depend on which one ran; numba's ``exp`` may differ from numpy's in
the last bit, which moves a centroid by far less than 1e-10 px. Loaded on first use through
:func:`.compiled.window_kernels` (importing startrack does not import numba); cached on disk
(``cache=True``); numpy's error model (a division by zero gives inf or NaN, as in numpy).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def windowed_iterate(signal, x0, y0, inv, cx, cy, max_iterations, tolerance, max_step):
    """The Newton iteration of :func:`.centroid_windowed._iterate`, in place on ``cx``, ``cy``.

    ``signal`` (N, S, S) float64 (0 on invalid pixels); ``x0``, ``y0`` (N,) the windows' first
    column and row; ``inv`` (N,) the weight's ``-1 / (2 s_w^2)``; ``cx``, ``cy`` (N,) float64 the
    starting centres. All windows step together until every step of every window is below
    ``tolerance`` px (at most ``max_iterations`` steps, each clipped to ``max_step`` px). Returns
    the last weighted sum ``sum w S`` (N,).
    """
    n, s = signal.shape[0], signal.shape[1]
    total = np.zeros(n)
    m = np.empty(5)
    axes = np.empty((4, s))
    for _ in range(max_iterations):
        converged = True
        for w in range(n):
            _weights(x0[w], cx[w], inv[w], axes[0], axes[1])
            _weights(y0[w], cy[w], inv[w], axes[2], axes[3])
            _moments(signal[w], axes, m)
            total[w] = m[0]
            step_x, step_y = _newton_step(m, inv[w], max_step)
            cx[w] += step_x
            cy[w] += step_y
            converged = converged and abs(step_x) < tolerance and abs(step_y) < tolerance
        if converged:
            break
    return total


@njit(cache=True, error_model="numpy")
def _weights(first, centre, inv, weight, offset):
    """Offsets ``first + k - centre`` of a window's pixels along one axis and their Gaussian
    weights ``exp(offset^2 inv)``, written into ``offset`` and ``weight`` (S,)."""
    for k in range(offset.size):
        d = (first + np.float64(k)) - centre
        offset[k] = d
        weight[k] = np.exp(d * d * inv)


@njit(cache=True, error_model="numpy")
def _moments(q, axes, m):
    """Moments ``m = (M00, M01, M10, M02, M20)`` of one window ``q`` (S, S) under the separable
    weights ``axes = (wx, dx, wy, dy)`` (4, S), ``M[a, b] = sum_j wy dy^a sum_i q wx dx^b``: the
    sums of :func:`.frame_kernels.separable_moments` in its order."""
    wx, dx, wy, dy = axes[0], axes[1], axes[2], axes[3]
    m00 = m01 = m02 = m10 = m20 = 0.0
    for j in range(q.shape[0]):
        a0 = a1 = a2 = 0.0
        for i in range(q.shape[1]):
            v = q[j, i] * wx[i]
            a0 += v
            a1 += v * dx[i]
            a2 += v * dx[i] * dx[i]
        y0 = wy[j]
        y1 = y0 * dy[j]
        y2 = y1 * dy[j]
        m00 += y0 * a0
        m01 += y0 * a1
        m02 += y0 * a2
        m10 += y1 * a0
        m20 += y2 * a0
    m[0], m[1], m[2], m[3], m[4] = m00, m01, m10, m02, m20


@njit(cache=True, error_model="numpy")
def _newton_step(m, inv, max_step):
    """The step (x, y), px, of one window from its moments ``m`` (:func:`_moments`): the first
    moment over the sum times the gain ``1 / (1 - v / s_w^2)`` in [1, 4] (2 where it is not
    finite), 0 where not finite, clipped to +-``max_step``."""
    total = m[0]
    v = (m[3] + m[4]) / (2.0 * total)
    gain = 1.0 / (1.0 + 2.0 * v * inv)
    gain = 2.0 if np.isnan(gain) else min(max(gain, 1.0), 4.0)
    return _clipped(m[1] / total * gain, max_step), _clipped(m[2] / total * gain, max_step)


@njit(cache=True, error_model="numpy")
def _clipped(step, max_step):
    """``step`` clipped to +-``max_step``, 0 where it is not finite."""
    if not np.isfinite(step):
        return 0.0
    return min(max(step, -max_step), max_step)
