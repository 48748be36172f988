"""Maximum-likelihood centroid: a pixel-integrated Gaussian fitted to each star's window.

Huffman 2006 §4.2.2 eqs. 4.3-4.13 (after Winick): the mean value of
pixel (i, j) is ``F g_i(x, s) g_j(y, s) + B`` with ``g_i`` the share of a Gaussian of width s
in pixel i (:mod:`._crb`), and the counts are Poisson plus read noise. The likelihood's score
equations are those of weighted least squares with weights ``1 / var_i`` re-evaluated at the
current model (iteratively reweighted least squares), ``var_i = noise^2 + max(model_i - B, 0)
/ gain``: with the gain known this is the seed's Poisson MLE; without it, the pixels have the
uniform background noise and the fit is the Gaussian-noise MLE.

Parameters: x, y, F, B and, unless the PSF width is given, s. All N stars are fitted at once with
a batched Levenberg-Marquardt (the (N, P, P) normal equations solved together), starting from
the weighted sum, as the seed's design starts the MLE from the WS estimate. The 1-sigma errors
are the square roots of the diagonal of the inverse Fisher matrix ``(J^T W J)^-1`` at the
solution (the fit covariance), or of the residual-based sandwich covariance when it is larger
(without the gain the weights hold only the background noise).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.special import erf

from ._centroid_windowed import pixel_variance
from ._windows import Centroids, Windows

ITERATIONS = 12
MIN_SIGMA_PX, MAX_SIGMA_FRACTION = 0.25, 0.6
"""Bounds of a fitted PSF width: px, and fraction of the window's half-width."""
_SQRT2 = math.sqrt(2.0)
_INV_SQRT_2PI = 1.0 / math.sqrt(2.0 * math.pi)


def _fractions(centres: NDArray, edges0: NDArray, s: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Per pixel of a window axis: Gaussian share g, dg/dc and dg/ds; (N, S) each.

    ``edges0`` (N, S + 1) are the pixel edges, ``centres`` (N,) the star's position, ``s`` (N,)
    its width."""
    u = (edges0 - centres[:, None]) / s[:, None]
    cdf = 0.5 * erf(u / _SQRT2)
    pdf = _INV_SQRT_2PI * np.exp(-0.5 * u * u)
    return np.diff(cdf, axis=1), -np.diff(pdf, axis=1) / s[:, None], \
        -np.diff(pdf * u, axis=1) / s[:, None]


def _model(p: NDArray, ex: NDArray, ey: NDArray, fit_sigma: bool
           ) -> tuple[NDArray, NDArray]:
    """Model windows (N, S, S) and Jacobian (N, P, S, S) at parameters p (N, P)."""
    gx, dgx, dsx = _fractions(p[:, 0], ex, p[:, 4])
    gy, dgy, dsy = _fractions(p[:, 1], ey, p[:, 4])
    f = p[:, 2][:, None, None]
    shape = gy[:, :, None] * gx[:, None, :]
    jac = [f * gy[:, :, None] * dgx[:, None, :], f * dgy[:, :, None] * gx[:, None, :], shape,
           np.ones_like(shape)]
    if fit_sigma:
        jac.append(f * (dsy[:, :, None] * gx[:, None, :] + gy[:, :, None] * dsx[:, None, :]))
    return f * shape + p[:, 3][:, None, None], np.stack(jac, axis=1)


def _chi2(data: NDArray, model: NDArray, weight: NDArray) -> NDArray:
    return (weight * (data - model) ** 2).sum(axis=(1, 2))


def mle_centroid(windows: Windows, level: NDArray, noise: NDArray, x_start: NDArray,
                 y_start: NDArray, flux_start: NDArray, psf_sigma_px: NDArray | float, *,
                 fit_sigma: bool = True, gain_e_per_adu: float | None = None) -> Centroids:
    """Fit x, y, flux, background (and PSF width) to N windows (module docstring).

    Parameters
    ----------
    windows : Windows
        Pixel windows around the stars (NaN pixels get no weight).
    level, noise : ndarray, shape (N,)
        Starting background and the background's pixel noise, image units.
    x_start, y_start, flux_start : ndarray, shape (N,)
        Starting position (our pixel convention) and flux.
    psf_sigma_px : float or ndarray, shape (N,)
        PSF width: the known value, or the starting value when ``fit_sigma``.
    fit_sigma : bool
        Fit the PSF width too (the seed's MLE assumes it known).
    gain_e_per_adu : float, optional
        Electrons per image unit; adds the star's Poisson variance to the weights.

    Returns
    -------
    Centroids
        ``flux`` is the fitted F; ``psf_sigma_px`` the fitted (or given) width; ``ok`` is False
        where the fit did not converge to a finite solution inside the window.
    """
    n, size = len(windows), windows.values.shape[1]
    xs, ys = windows.coords()
    ex = xs[:, 0, :] - 0.5
    ex = np.concatenate([ex, ex[:, -1:] + 1.0], axis=1)  # (N, S + 1) pixel edges
    ey = ys[:, :, 0] - 0.5
    ey = np.concatenate([ey, ey[:, -1:] + 1.0], axis=1)
    data = np.nan_to_num(windows.values)
    valid = np.isfinite(windows.values)
    p = np.stack([x_start, y_start, np.maximum(flux_start, 1e-9),
                  np.asarray(level, float), np.broadcast_to(psf_sigma_px, (n,))], axis=1)
    p = p.astype(np.float64)
    npar = 5 if fit_sigma else 4
    lam = np.full(n, 1e-3)
    model, jac = _model(p, ex, ey, fit_sigma)
    weight = valid / pixel_variance(model - p[:, 3][:, None, None], noise, gain_e_per_adu)
    chi2 = _chi2(data, model, weight)
    for _ in range(ITERATIONS):
        step = _lm_step(data - model, jac, weight, lam, npar)
        trial = _bounded(p.copy(), step, npar, windows, size)
        t_model, t_jac = _model(trial, ex, ey, fit_sigma)
        t_chi2 = _chi2(data, t_model, weight)
        better = t_chi2 <= chi2
        p[better], model[better], jac[better], chi2[better] = (
            trial[better], t_model[better], t_jac[better], t_chi2[better])
        lam = np.where(better, lam * 0.3, lam * 10.0)
        weight = valid / pixel_variance(model - p[:, 3][:, None, None], noise, gain_e_per_adu)
    return _result(p, jac, weight, npar, windows, (data - model) * valid)


def _lm_step(residual: NDArray, jac: NDArray, weight: NDArray, lam: NDArray, npar: int) -> NDArray:
    """Levenberg-Marquardt step (N, P) from the batched normal equations."""
    j = jac.reshape(jac.shape[0], jac.shape[1], -1)[:, :npar]
    w = weight.reshape(weight.shape[0], -1)
    a = np.einsum("npm,nqm,nm->npq", j, j, w)
    g = np.einsum("npm,nm->np", j, w * residual.reshape(residual.shape[0], -1))
    diag = np.einsum("npp->np", a)
    a = a + (lam[:, None] * diag)[:, :, None] * np.eye(npar)
    try:
        return np.linalg.solve(a, g[:, :, None])[:, :, 0]
    except np.linalg.LinAlgError:
        return np.stack([_safe_solve(a[i], g[i]) for i in range(len(a))])


def _safe_solve(a: NDArray, g: NDArray) -> NDArray:
    try:
        return np.linalg.solve(a, g)
    except np.linalg.LinAlgError:
        return np.zeros_like(g)


def _bounded(p: NDArray, step: NDArray, npar: int, windows: Windows, size: int) -> NDArray:
    """Apply ``step``, keeping the star inside its window and the width within bounds."""
    p[:, :npar] += np.nan_to_num(step)
    p[:, 0] = np.clip(p[:, 0], windows.x0 - 0.5, windows.x0 + size - 0.5)
    p[:, 1] = np.clip(p[:, 1], windows.y0 - 0.5, windows.y0 + size - 0.5)
    p[:, 2] = np.maximum(p[:, 2], 1e-9)
    p[:, 4] = np.clip(p[:, 4], MIN_SIGMA_PX, max(MIN_SIGMA_PX, MAX_SIGMA_FRACTION * (size // 2)))
    return p


def _result(p: NDArray, jac: NDArray, weight: NDArray, npar: int, windows: Windows,
            residual: NDArray) -> Centroids:
    """Centroids with the fit covariance's position errors: the larger of the model's
    ``(J^T W J)^-1`` and the sandwich ``A^-1 (J^T W diag(r^2) W J) A^-1`` built from the
    residuals r (which holds the stars' shot noise when the gain is unknown)."""
    j = jac.reshape(jac.shape[0], jac.shape[1], -1)[:, :npar]
    w = weight.reshape(weight.shape[0], -1)
    info = np.einsum("npm,nqm,nm->npq", j, j, w)
    wr2 = (w * residual.reshape(residual.shape[0], -1)) ** 2
    meat = np.einsum("npm,nqm,nm->npq", j, j, wr2)
    with np.errstate(invalid="ignore", divide="ignore"):
        det_ok = np.abs(np.linalg.det(info)) > 0
        info[~det_ok] = np.eye(npar)
        cov = np.linalg.inv(info)
        robust = cov @ meat @ cov
        var = 0.5 * np.maximum(cov[:, 0, 0] + cov[:, 1, 1], robust[:, 0, 0] + robust[:, 1, 1])
        sigma = np.sqrt(np.maximum(var, 0.0))
    half = windows.half
    inside = (np.abs(p[:, 0] - (windows.x0 + half)) < half) & \
        (np.abs(p[:, 1] - (windows.y0 + half)) < half)
    ok = det_ok & inside & np.all(np.isfinite(p), axis=1) & (p[:, 2] > 1e-9)
    return Centroids(x=p[:, 0].copy(), y=p[:, 1].copy(), flux=p[:, 2].copy(),
                     sigma_px=np.where(det_ok, sigma, np.nan), psf_sigma_px=p[:, 4].copy(), ok=ok)
