"""Iteratively windowed weighted centroid (Gaussian-weighted first moment).

The window follows the estimate: with ``w_i = exp(-|r_i - c|^2 / (2 s_w^2))`` and ``S_i`` the
background-subtracted pixel values, iterate

    c <- c + g * sum_i w_i S_i (r_i - c) / sum_i w_i S_i,     g = 1 / (1 - v / s_w^2)

until the step is below :data:`TOLERANCE_PX`, with v the windowed second moment per axis (a
Newton step for a Gaussian star: g is 2 when the window matches the star, SExtractor's ``XWIN``
factor; the fixed point ``sum w S (r - c) = 0`` does not depend on g). That fixed point is the
stationary point of the cross-correlation of the image with a Gaussian of width ``s_w``, so
with ``s_w`` equal to the star's PSF width it is the maximum-likelihood centroid of a
background-limited Gaussian star (ignoring pixelation): close to the Cramér-Rao bound
(:mod:`.crb`) at a fraction of a fit's cost. Unlike the thresholded weighted sum it has no
pixel-phase bias from a threshold cutting the wings, and far-out noisy pixels get no weight.
Seed 000 §4.2.2 (notes §1.8) mentions the fixed-window mass-moment variant (DIGISTAR /
Samaan); this is its iterated, tapered form. For undersampled stars (PSF sigma 0.7 px) the
Gaussian window has a pixel-phase bias of about 0.01 px (``benchmarks/detect_accuracy.py``).

Uncertainty (per axis): linearising the fixed-point equation ``psi(c) = sum w S (x - c) = 0``,

    var(c) = sum_i w_i^2 (x_i - c)^2 var_i / D^2,   D = sum_i w_i S_i * s_w^2 / (s_e^2 + s_w^2)

with ``var_i`` the pixel noise variance (plus the signal's shot noise when the gain is known)
and ``s_e^2 = s_p^2 + 1/12`` the variance of the pixel-integrated PSF (D is the expected value
of ``-d psi / dc`` for a Gaussian star). Without the gain, the sum's empirical value from the
residuals of a Gaussian star is taken when it is larger (the bright stars' own shot noise, or a
PSF that is not Gaussian); ``s_p``, when not given, is the median over the stars of the width
found from the windowed second moment ``v = s_e^2 s_w^2 / (s_e^2 + s_w^2)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.special import erf

from .windows import Centroids, Windows

TOLERANCE_PX = 1e-3
MAX_ITERATIONS = 20
MAX_STEP_PX = 1.0
"""A single iteration moves the window by at most this much (keeps noise from throwing it)."""


def pixel_variance(signal: NDArray, noise: NDArray, gain_e_per_adu: float | None) -> NDArray:
    """Variance of each window pixel, image units^2: ``noise^2`` plus, when the gain is known,
    the star's shot noise ``max(signal, 0) / gain``. ``noise`` has shape (N,)."""
    var = np.broadcast_to((np.asarray(noise, dtype=float) ** 2)[:, None, None], signal.shape)
    if gain_e_per_adu is None:
        return var
    return var + np.maximum(np.nan_to_num(signal), 0.0) / gain_e_per_adu


def windowed_centroid(windows: Windows, level: NDArray, noise: NDArray, x_start: NDArray,
                      y_start: NDArray, window_sigma_px: NDArray, *,
                      psf_sigma_px: NDArray | None = None,
                      gain_e_per_adu: float | None = None) -> Centroids:
    """Gaussian-windowed centroid of N windows (module docstring).

    Parameters
    ----------
    windows : Windows
        N pixel windows (NaN pixels ignored).
    level, noise : ndarray, shape (N,)
        Background level and pixel noise (standard deviation) of each window, image units.
    x_start, y_start : ndarray, shape (N,)
        Starting estimate (e.g. the weighted sum), our pixel convention.
    window_sigma_px : ndarray, shape (N,) or scalar
        Width of the Gaussian weight (best: the PSF's standard deviation).
    psf_sigma_px : ndarray, shape (N,), optional
        PSF width for the uncertainty; ``window_sigma_px`` when None.
    gain_e_per_adu : float, optional
        Electrons per image unit, to add the signal's shot noise to the pixel variance.

    Returns
    -------
    Centroids
        ``flux`` is NaN (the caller keeps its own); ``psf_sigma_px`` is the window width;
        ``ok`` is False where the weighted signal was not positive or the estimate left the
        window.
    """
    n = len(windows)
    sw = np.broadcast_to(np.asarray(window_sigma_px, dtype=float), (n,))[:, None, None]
    signal = windows.values - np.asarray(level, dtype=float)[:, None, None]
    valid = np.isfinite(signal)
    signal = np.where(valid, signal, 0.0)
    cx, cy, total = _iterate(windows, signal, np.array(x_start, dtype=float),
                             np.array(y_start, dtype=float), sw[:, 0, 0])
    sigma = _sigma(windows, signal, valid, cx, cy, sw, psf_sigma_px, noise, gain_e_per_adu)
    half = windows.half
    inside = (np.abs(cx - (windows.x0 + half)) <= half) & (np.abs(cy - (windows.y0 + half)) <= half)
    ok = inside & (total > 0) & np.isfinite(sigma)
    return Centroids(x=cx, y=cy, flux=np.full(n, np.nan), sigma_px=sigma,
                     psf_sigma_px=sw[:, 0, 0].copy(), ok=ok)


def _iterate(windows: Windows, signal: NDArray, cx: NDArray, cy: NDArray, sw: NDArray
             ) -> tuple[NDArray, NDArray, NDArray]:
    """The fixed-point (Newton) iteration of the module docstring; returns cx, cy and the last
    weighted sum. The Gaussian weight is separable, so each step is two small contractions
    of the (N, S, S) windows with per-axis weights instead of (N, S, S) exponentials."""
    k = np.arange(signal.shape[1], dtype=np.float64)
    px, py = windows.x0[:, None] + k, windows.y0[:, None] + k  # (N, S) pixel coordinates
    inv = (-0.5 / (sw * sw))[:, None]
    total = np.zeros(len(cx))
    for _ in range(MAX_ITERATIONS):
        dx, dy = px - cx[:, None], py - cy[:, None]
        wx, wy = np.exp(dx * dx * inv), np.exp(dy * dy * inv)
        rows = signal @ np.stack([wx, wx * dx, wx * dx * dx], axis=2)  # (N, S, 3): x sums
        total = (rows[:, :, 0] * wy).sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            first = np.stack([(rows[:, :, 1] * wy).sum(axis=1),
                              (rows[:, :, 0] * wy * dy).sum(axis=1)]) / total
            v = ((rows[:, :, 2] * wy).sum(axis=1)
                 + (rows[:, :, 0] * wy * dy * dy).sum(axis=1)) / (2.0 * total)
            gain = np.clip(1.0 / (1.0 - v * (-2.0 * inv[:, 0])), 1.0, 4.0)  # 1 / (1 - v / s_w^2)
        step = first * np.where(np.isfinite(gain), gain, 2.0)
        step[~np.isfinite(step)] = 0.0
        np.clip(step, -MAX_STEP_PX, MAX_STEP_PX, out=step)
        cx += step[0]
        cy += step[1]
        if np.all(np.abs(step) < TOLERANCE_PX):
            break
    return cx, cy, total


def _weights(xs: NDArray, ys: NDArray, cx: NDArray, cy: NDArray, sw: NDArray) -> NDArray:
    """Gaussian weights of width ``sw`` about (cx, cy), shape (N, S, S)."""
    inv = -0.5 / (sw * sw)
    return np.exp((xs - cx[:, None, None]) ** 2 * inv) * np.exp((ys - cy[:, None, None]) ** 2 * inv)


def _sigma(windows: Windows, signal: NDArray, valid: NDArray, cx: NDArray, cy: NDArray,
           sw: NDArray, psf_sigma_px: NDArray | None, noise: NDArray,
           gain_e_per_adu: float | None) -> NDArray[np.float64]:
    """Linearised 1-sigma error per axis (module docstring), the mean of the x and y terms.

    The numerator takes the larger of the noise model's value and its empirical value from the
    residuals ``S - A w`` (A fitted by least squares): when the gain is unknown the model has
    only the background noise, and the residuals add the bright stars' shot noise.
    """
    xs, ys = windows.coords()
    w = _weights(xs, ys, cx, cy, sw) * valid
    var = pixel_variance(signal, noise, gain_e_per_adu)
    r2 = (xs - cx[:, None, None]) ** 2 + (ys - cy[:, None, None]) ** 2
    sw2 = sw[:, 0, 0] ** 2
    if sw2.size == 0:
        return np.zeros(0)
    if psf_sigma_px is None:  # one width for the frame: a single star's estimate is noisy
        sp2 = np.full(sw2.shape, np.median(_psf_variance(w, signal, r2, sw2)))
    else:
        sp2 = np.broadcast_to(np.asarray(psf_sigma_px, float) ** 2, sw2.shape)
    d = (w * signal).sum(axis=(1, 2)) * sw2 / (sp2 + 1.0 / 12 + sw2)
    lever = w * w * r2
    with np.errstate(invalid="ignore", divide="ignore"):
        shape = _pixel_gaussian(xs, ys, cx, cy, np.sqrt(sp2)) * valid
        residual = _residual(signal, shape, valid)
        model = (lever * var).sum(axis=(1, 2))
        empirical = (lever * residual * residual).sum(axis=(1, 2))
        num = 0.5 * np.maximum(model, empirical)
        return np.where(d > 0, np.sqrt(num) / d, np.nan)


def _residual(signal: NDArray, shape: NDArray, valid: NDArray) -> NDArray:
    """``signal - (A shape + B)`` with A, B fitted by linear least squares per window."""
    n = valid.sum(axis=(1, 2))
    sx, sy = shape.sum(axis=(1, 2)), (signal * valid).sum(axis=(1, 2))
    sxx, sxy = (shape * shape).sum(axis=(1, 2)), (shape * signal).sum(axis=(1, 2))
    det = n * sxx - sx * sx
    a = (n * sxy - sx * sy) / det
    b = (sy - a * sx) / n
    return (signal - a[:, None, None] * shape - b[:, None, None]) * valid


def _pixel_gaussian(xs: NDArray, ys: NDArray, cx: NDArray, cy: NDArray, s: NDArray) -> NDArray:
    """Pixel-integrated unit Gaussian of width ``s`` (N,) centred on (cx, cy), (N, S, S)."""
    scale = 1.0 / (np.sqrt(2.0) * s)[:, None]
    def share(coords: NDArray, centre: NDArray) -> NDArray:
        d = coords - centre[:, None]
        return 0.5 * (erf((d + 0.5) * scale) - erf((d - 0.5) * scale))
    return share(ys[:, :, 0], cy)[:, :, None] * share(xs[:, 0, :], cx)[:, None, :]


def _psf_variance(w: NDArray, signal: NDArray, r2: NDArray, sw2: NDArray) -> NDArray:
    """PSF variance s_p^2 from the windowed second moment: a pixel-integrated Gaussian is close
    to a Gaussian of variance s_e^2 = s_p^2 + 1/12, and its moment under the Gaussian weight is
    v = s_e^2 s_w^2 / (s_e^2 + s_w^2). Clipped to [s_w^2 / 4, 4 s_w^2]."""
    with np.errstate(invalid="ignore", divide="ignore"):
        v = 0.5 * (w * signal * r2).sum(axis=(1, 2)) / (w * signal).sum(axis=(1, 2))
        sp2 = v * sw2 / (sw2 - v) - 1.0 / 12
    sp2 = np.where(np.isfinite(sp2) & (v < sw2), sp2, 4.0 * sw2)
    return np.clip(sp2, 0.25 * sw2, 4.0 * sw2)
