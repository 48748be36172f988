"""The compiled loops of the windowed centroider (numba): the fixed-point iteration of
:mod:`._centroid_windowed` over a stack of windows, and its linearised uncertainty.

Each loop gives the numbers of the numpy expressions it replaces, operation for operation (the
separable moments summed along x first, then along y, as :func:`.frame_kernels.separable_moments`
does), so a centroid does not depend on which one ran; numba's ``exp`` and ``erf`` may differ
from numpy's and scipy's in the last bit, which moves a centroid by far less than 1e-10 px (and
its uncertainty by far less than a relative 1e-9, what ``tests/detect/test_detect_window_kernels.py``
checks against the numpy versions it keeps as the reference). Loaded on first use through
:func:`.compiled.window_kernels` (importing startrack does not import numba); cached on disk
(``cache=True``); numpy's error model (a division by zero gives inf or NaN, as in numpy).
"""

from __future__ import annotations

import math

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


@njit(cache=True, error_model="numpy")
def windowed_sigma(signal, valid, x0, y0, inv, cx, cy, sw2, sp2, noise, gain):
    """The linearised 1-sigma error of :func:`.centroid_windowed._sigma` for each window, px.

    ``signal`` (N, S, S) float64 (0 on invalid pixels), ``valid`` (N, S, S) bool; ``x0``, ``y0``,
    ``inv``, ``cx``, ``cy`` as :func:`windowed_iterate`'s (the converged centres); ``sw2`` (N,)
    the window's variance, px^2; ``sp2`` (N,) the PSF's variance, or an empty array for the
    median over the windows of :func:`_psf_variance`; ``noise`` (N,) the pixel noise; ``gain``
    electrons per image unit, or 0 when unknown (no shot-noise term). Returns (N,) float64, NaN
    where the weighted sum is not positive."""
    n, s = signal.shape[0], signal.shape[1]
    out = np.empty(n)
    axes, squared = np.empty((n, 4, s)), np.empty((4, s))
    share, edges = np.empty((2, s)), np.empty(s + 1)
    shape, stack = np.empty((s, s)), np.empty((2, s, s))
    m, lever = np.empty((n, 5)), np.empty(5)
    for w in range(n):
        _weights(x0[w], cx[w], inv[w], axes[w, 0], axes[w, 1])
        _weights(y0[w], cy[w], inv[w], axes[w, 2], axes[w, 3])
        _moments(signal[w], axes[w], m[w])
    if sp2.size == 0 and n > 0:  # one width for the frame: a single star's estimate is noisy
        sp2 = np.full(n, np.median(_psf_variance(m, sw2)))
    for w in range(n):
        d = m[w, 0] * sw2[w] / (sp2[w] + 1.0 / 12 + sw2[w])
        scale = 1.0 / (np.sqrt(2.0) * np.sqrt(sp2[w]))
        _pixel_share(axes[w, 3], scale, edges, share[0])
        _pixel_share(axes[w, 1], scale, edges, share[1])
        _fitted_shape(valid[w], share, shape)
        _variance_and_residual(signal[w], valid[w], shape, noise[w], gain, stack)
        for k in range(4):
            squared[k] = axes[w, k] * axes[w, k] if k % 2 == 0 else axes[w, k]
        _moments(stack[0], squared, lever)
        model = lever[3] + lever[4]
        _moments(stack[1], squared, lever)
        empirical = lever[3] + lever[4]
        num = 0.5 * (model if (model > empirical or np.isnan(model)) else empirical)  # np.maximum's NaN
        out[w] = np.sqrt(num) / d if d > 0 else np.nan
    return out


@njit(cache=True, error_model="numpy")
def _psf_variance(m, sw2):
    """PSF variance s_p^2 (N,) from the windowed second moments ``m`` (N, 5) (:func:`_moments`)
    and window variances ``sw2`` (N,): a pixel-integrated Gaussian is close to a Gaussian of
    variance s_e^2 = s_p^2 + 1/12, and its moment under the Gaussian weight is
    v = s_e^2 s_w^2 / (s_e^2 + s_w^2). Clipped to [s_w^2 / 4, 4 s_w^2] (4 s_w^2 where v is not
    below s_w^2 or not finite)."""
    out = np.empty(sw2.size)
    for w in range(sw2.size):
        v = 0.5 * (m[w, 3] + m[w, 4]) / m[w, 0]
        value = v * sw2[w] / (sw2[w] - v) - 1.0 / 12
        if not (np.isfinite(value) and v < sw2[w]):
            value = 4.0 * sw2[w]
        out[w] = min(max(value, 0.25 * sw2[w]), 4.0 * sw2[w])
    return out


@njit(cache=True, error_model="numpy")
def _pixel_share(offset, scale, edges, share):
    """The share of a unit Gaussian (``scale`` = 1 / (sqrt(2) s)) falling on each pixel whose
    centre is at ``offset`` (S,) from the Gaussian's: half the erf differences at the S + 1 pixel
    edges, written into ``share`` (S,)."""
    s = offset.size
    for k in range(s):
        edges[k] = (offset[k] - 0.5) * scale
    edges[s] = (offset[s - 1] + 0.5) * scale
    for k in range(s):
        share[k] = 0.5 * (math.erf(edges[k + 1]) - math.erf(edges[k]))


@njit(cache=True, error_model="numpy")
def _fitted_shape(valid, share, shape):
    """The pixel-integrated Gaussian ``share[0][j] share[1][i]`` on the valid pixels (0 elsewhere),
    written into ``shape`` (S, S)."""
    for j in range(shape.shape[0]):
        for i in range(shape.shape[1]):
            shape[j, i] = share[0, j] * share[1, i] if valid[j, i] else 0.0


@njit(cache=True, error_model="numpy")
def _variance_and_residual(signal, valid, shape, noise, gain, stack):
    """``stack[0]``: each valid pixel's variance (``noise^2``, plus ``max(signal, 0) / gain``
    when ``gain`` > 0); ``stack[1]``: the squared residual of the least-squares fit
    ``signal ~ A shape + B`` over the valid pixels; both 0 on invalid pixels."""
    count = sx = sy = sxx = sxy = 0.0
    for j in range(shape.shape[0]):
        for i in range(shape.shape[1]):
            if valid[j, i]:
                g, v = shape[j, i], signal[j, i]
                count += 1.0
                sx += g
                sy += v
                sxx += g * g
                sxy += g * v
    a = (count * sxy - sx * sy) / (count * sxx - sx * sx)
    b = (sy - a * sx) / count
    for j in range(shape.shape[0]):
        for i in range(shape.shape[1]):
            if valid[j, i]:
                v = signal[j, i]
                r = v - a * shape[j, i] - b
                stack[0, j, i] = noise * noise + (max(v, 0.0) / gain if gain > 0 else 0.0)
                stack[1, j, i] = r * r
            else:
                stack[0, j, i] = stack[1, j, i] = 0.0
