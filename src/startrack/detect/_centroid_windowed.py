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
(:mod:`._crb`) at a fraction of a fit's cost. Unlike the thresholded weighted sum it has no
pixel-phase bias from a threshold cutting the wings, and far-out noisy pixels get no weight.
Huffman 2006 §4.2.2 mentions the fixed-window mass-moment variant (DIGISTAR /
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

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._compiled import window_kernels
from ._windows import Centroids, Windows

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
                      y_start: NDArray, window_sigma_px: NDArray | float, *,
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
    sw = np.full(n, window_sigma_px, dtype=np.float64)  # a fresh array: the result's psf_sigma_px
    signal = windows.values - np.asarray(level, dtype=float)[:, None, None]
    valid = np.isfinite(signal)
    signal[~valid] = 0.0
    axes = _Axes.of(windows, sw)
    cx, cy, total = _iterate(axes, signal, np.array(x_start, dtype=float), np.array(y_start, dtype=float))
    sigma = _sigma(axes, signal, valid, cx, cy, psf_sigma_px, noise, gain_e_per_adu)
    half = windows.half
    inside = (np.abs(cx - (windows.x0 + half)) <= half) & (np.abs(cy - (windows.y0 + half)) <= half)
    ok = inside & (total > 0) & np.isfinite(sigma)
    return Centroids(x=cx, y=cy, flux=np.full(n, np.nan), sigma_px=sigma, psf_sigma_px=sw, ok=ok)


@dataclass(frozen=True)
class _Axes:
    """The first column and row of N windows and their Gaussian weight's ``-1 / (2 s_w^2)``, shape
    (N,) float64 each, as the compiled loops take them; ``sw2`` the window variance s_w^2, px^2."""

    x0: NDArray
    y0: NDArray
    inv: NDArray
    sw2: NDArray

    @classmethod
    def of(cls, windows: Windows, sw: NDArray) -> _Axes:
        sw2 = sw * sw
        return cls(np.asarray(windows.x0, dtype=np.float64), np.asarray(windows.y0, dtype=np.float64),
                   -0.5 / sw2, sw2)


def _iterate(axes: _Axes, signal: NDArray, cx: NDArray, cy: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """The fixed-point (Newton) iteration of the module docstring; returns cx, cy and the last
    weighted sum. Every window steps until all steps are below :data:`TOLERANCE_PX`; each step
    takes the separable weighted moments of the signal (one compiled loop,
    :func:`.window_kernels.windowed_iterate`)."""
    total = window_kernels().windowed_iterate(
        np.ascontiguousarray(signal, dtype=np.float64), axes.x0, axes.y0, axes.inv, cx, cy,
        MAX_ITERATIONS, TOLERANCE_PX, MAX_STEP_PX)
    return cx, cy, total


def _sigma(axes: _Axes, signal: NDArray, valid: NDArray, cx: NDArray, cy: NDArray, psf_sigma_px: NDArray | None,
           noise: NDArray, gain_e_per_adu: float | None) -> NDArray[np.float64]:
    """Linearised 1-sigma error per axis (module docstring), the mean of the x and y terms, about
    the centres (cx, cy).

    The numerator takes the larger of the noise model's value and its empirical value from the
    residuals ``S - A w`` (A fitted by least squares): when the gain is unknown the model has
    only the background noise, and the residuals add the bright stars' shot noise. The sums
    over ``w^2 r^2`` are the separable moments of the squared axis weights. One compiled loop
    over the windows (:func:`.window_kernels.windowed_sigma`).
    """
    if axes.sw2.size == 0:
        return np.zeros(0)
    sp2 = np.zeros(0) if psf_sigma_px is None else \
        np.full(axes.sw2.shape, np.asarray(psf_sigma_px, float) ** 2, dtype=np.float64)
    noise = np.full(axes.sw2.shape, noise, dtype=np.float64)
    return window_kernels().windowed_sigma(np.ascontiguousarray(signal, dtype=np.float64), np.ascontiguousarray(valid),
                                           axes.x0, axes.y0, axes.inv, cx, cy, axes.sw2, sp2, noise,
                                           float(gain_e_per_adu or 0.0))
