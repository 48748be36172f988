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
from scipy.special import erf

from ._compiled import window_kernels
from ._windows import Centroids, Windows, fast_median, separable_moments

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
    sw = np.broadcast_to(np.asarray(window_sigma_px, dtype=float), (n,))
    signal = windows.values - np.asarray(level, dtype=float)[:, None, None]
    valid = np.isfinite(signal)
    signal[~valid] = 0.0
    axes = _Axes.of(windows, sw)
    cx, cy, total = _iterate(axes, signal, np.array(x_start, dtype=float), np.array(y_start, dtype=float))
    sigma = _sigma(axes.at(cx, cy), signal, valid, sw * sw, psf_sigma_px, noise, gain_e_per_adu)
    half = windows.half
    inside = (np.abs(cx - (windows.x0 + half)) <= half) & (np.abs(cy - (windows.y0 + half)) <= half)
    ok = inside & (total > 0) & np.isfinite(sigma)
    return Centroids(x=cx, y=cy, flux=np.full(n, np.nan), sigma_px=sigma, psf_sigma_px=sw.copy(), ok=ok)


@dataclass(frozen=True)
class _Centred:
    """Per-axis offsets of N windows' pixels from centres (cx, cy) and their Gaussian weights,
    shape (N, S) each."""

    dx: NDArray
    dy: NDArray
    wx: NDArray
    wy: NDArray


@dataclass(frozen=True)
class _Axes:
    """Per-axis pixel coordinates of N windows, shape (N, S) each, and the Gaussian weight's
    ``-1 / (2 s_w^2)``, shape (N, 1)."""

    px: NDArray
    py: NDArray
    inv: NDArray

    @classmethod
    def of(cls, windows: Windows, sw: NDArray) -> _Axes:
        k = np.arange(windows.values.shape[1], dtype=np.float64)
        return cls(windows.x0[:, None] + k, windows.y0[:, None] + k, (-0.5 / (sw * sw))[:, None])

    def at(self, cx: NDArray, cy: NDArray) -> _Centred:
        """Offsets and Gaussian weights about the centres (cx, cy), shape (N,) each."""
        dx, dy = self.px - cx[:, None], self.py - cy[:, None]
        return _Centred(dx, dy, np.exp(dx * dx * self.inv), np.exp(dy * dy * self.inv))


def _iterate(axes: _Axes, signal: NDArray, cx: NDArray, cy: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """The fixed-point (Newton) iteration of the module docstring; returns cx, cy and the last
    weighted sum. Every window steps until all steps are below :data:`TOLERANCE_PX`; each step
    takes the separable weighted moments of the signal (one compiled loop,
    :func:`.window_kernels.windowed_iterate`)."""
    total = window_kernels().windowed_iterate(
        np.ascontiguousarray(signal, dtype=np.float64), np.ascontiguousarray(axes.px[:, 0]),
        np.ascontiguousarray(axes.py[:, 0]),
        np.ascontiguousarray(axes.inv[:, 0]), cx, cy, MAX_ITERATIONS, TOLERANCE_PX, MAX_STEP_PX)
    return cx, cy, total


def _sigma(at: _Centred, signal: NDArray, valid: NDArray, sw2: NDArray, psf_sigma_px: NDArray | None,
           noise: NDArray, gain_e_per_adu: float | None) -> NDArray[np.float64]:
    """Linearised 1-sigma error per axis (module docstring), the mean of the x and y terms.

    The numerator takes the larger of the noise model's value and its empirical value from the
    residuals ``S - A w`` (A fitted by least squares): when the gain is unknown the model has
    only the background noise, and the residuals add the bright stars' shot noise. The sums
    over ``w^2 r^2`` are the separable moments of the squared axis weights.
    """
    if sw2.size == 0:
        return np.zeros(0)
    m = separable_moments(signal, at.wx, at.dx, at.wy, at.dy)  # signal is 0 on invalid pixels
    if psf_sigma_px is None:  # one width for the frame: a single star's estimate is noisy
        sp2 = np.full(sw2.shape, fast_median(_psf_variance(m, sw2)))
    else:
        sp2 = np.broadcast_to(np.asarray(psf_sigma_px, float) ** 2, sw2.shape)
    d = m[:, 0, 0] * sw2 / (sp2 + 1.0 / 12 + sw2)
    with np.errstate(invalid="ignore", divide="ignore"):
        shape = _pixel_gaussian(at, np.sqrt(sp2)) * valid
        residual = _residual(signal, shape, valid)
        var = pixel_variance(signal, noise, gain_e_per_adu) * valid
        lever = separable_moments(np.stack([var, residual * residual]), at.wx**2, at.dx, at.wy**2, at.dy)
        num = 0.5 * np.maximum(*(lever[:, :, 0, 2] + lever[:, :, 2, 0]))
        return np.where(d > 0, np.sqrt(num) / d, np.nan)


def _residual(signal: NDArray, shape: NDArray, valid: NDArray) -> NDArray:
    """``signal - (A shape + B)`` with A, B fitted by linear least squares per window
    (``signal`` and ``shape`` are 0 on invalid pixels)."""
    n, sx, sy, sxx, sxy = np.stack([valid, shape, signal, shape * shape, shape * signal]).sum(axis=(2, 3))
    det = n * sxx - sx * sx
    a = (n * sxy - sx * sy) / det
    b = (sy - a * sx) / n
    return (signal - a[:, None, None] * shape - b[:, None, None]) * valid


def _pixel_gaussian(at: _Centred, s: NDArray) -> NDArray:
    """Pixel-integrated unit Gaussian of width ``s`` (N,) centred on the axes' centre, (N, S, S):
    per axis, the differences of erf at the S + 1 pixel edges (both axes in one erf call)."""
    d = np.stack([at.dy, at.dx])  # (2, N, S)
    edges = np.concatenate([d - 0.5, d[:, :, -1:] + 0.5], axis=2) * (1.0 / (np.sqrt(2.0) * s))[:, None]
    share = 0.5 * np.diff(erf(edges), axis=2)
    return share[0][:, :, None] * share[1][:, None, :]


def _psf_variance(m: NDArray, sw2: NDArray) -> NDArray:
    """PSF variance s_p^2 from the windowed second moment (moments ``m`` of the signal, (N, 3, 3)):
    a pixel-integrated Gaussian is close to a Gaussian of variance s_e^2 = s_p^2 + 1/12, and its
    moment under the Gaussian weight is v = s_e^2 s_w^2 / (s_e^2 + s_w^2). Clipped to
    [s_w^2 / 4, 4 s_w^2]."""
    with np.errstate(invalid="ignore", divide="ignore"):
        v = 0.5 * (m[:, 0, 2] + m[:, 2, 0]) / m[:, 0, 0]
        sp2 = v * sw2 / (sw2 - v) - 1.0 / 12
    sp2 = np.where(np.isfinite(sp2) & (v < sw2), sp2, 4.0 * sw2)
    return np.clip(sp2, 0.25 * sw2, 4.0 * sw2)
