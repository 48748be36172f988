"""The Cramér-Rao bound on centroid accuracy for a pixel-integrated Gaussian star image.

No unbiased centroider can beat the bound; the benchmark (``benchmarks/detect_centroid_crb.py``)
divides each method's RMS error by it. Model (Huffman 2006 §4.2.2 eqs. 4.3-4.8,
after Winick 1986): the mean electrons in pixel (i, j) are

    mu_ij = F g_i(x) g_j(y) + B,     g_i(x) = Phi((i + 1/2 - x) / s) - Phi((i - 1/2 - x) / s)

(F star electrons, s the PSF's standard deviation, B sky + dark electrons per pixel, pixel i
covering [i - 1/2, i + 1/2]), and the count in each pixel is Poisson(mu) plus Gaussian read noise
of R electrons rms, approximated as Gaussian of variance ``mu + R**2``. The Fisher information
of the parameters theta = (x, y, F, B[, s]) is

    I_kl = sum_ij (d mu_ij / d theta_k)(d mu_ij / d theta_l) / (mu_ij + R**2)

(the variance's own dependence on theta adds a term of order 1 / (2 mu**2), negligible for the
counts here and left out, as in Winick's derivation). The bound on x is ``sqrt((I^-1)_xx)``: by
default with F and B unknown too (``nuisance=True``, the fair bound for a centroider that must
estimate them); with the PSF width unknown as well when ``fit_sigma``; with only x, y unknown
when ``nuisance=False``.

Closed forms for the two limits, with N_eff = 4 pi s**2 the noise-equivalent area (useful as a
check and in the docs; the sampled bound approaches them for s >~ 1 px):

* photon-limited (B = R = 0): sigma_x = s / sqrt(F);
* background-limited: sigma_x = sqrt(8 pi) s**2 sqrt(B + R**2) / F.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import erf

from ..errors import InvalidInputError, as_float_array

_SQRT2 = math.sqrt(2.0)
_INV_SQRT_2PI = 1.0 / math.sqrt(2.0 * math.pi)
STAMP_SIGMAS = 6.0
"""Half-width of the pixel stamp over which the information is summed, in PSF sigmas."""


def noise_equivalent_area(psf_sigma_px: ArrayLike) -> NDArray[np.float64]:
    """4 pi s^2: the number of pixels whose background noise a Gaussian star image collects."""
    return 4.0 * np.pi * np.asarray(psf_sigma_px, dtype=float) ** 2


def integrated_snr(flux_e: ArrayLike, psf_sigma_px: ArrayLike, background_e: ArrayLike = 0.0,
                   read_noise_e: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Signal-to-noise ratio of a whole star image (Huffman 2006 eq. 3.17 with the sky and read noise
    of the noise-equivalent area): ``F / sqrt(F + 4 pi s^2 (B + R^2))``.

    Parameters are electrons (flux in the star, background per pixel, read noise rms per pixel)
    and pixels; they broadcast against each other.
    """
    f = np.asarray(flux_e, dtype=float)
    var = f + noise_equivalent_area(psf_sigma_px) * (np.asarray(background_e, dtype=float)
                                                     + np.asarray(read_noise_e, dtype=float) ** 2)
    return f / np.sqrt(var)


def flux_for_snr(snr: ArrayLike, psf_sigma_px: ArrayLike, background_e: ArrayLike = 0.0,
                 read_noise_e: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Star electrons that give :func:`integrated_snr` equal to ``snr`` (its inverse)."""
    s2 = as_float_array(snr, "snr") ** 2
    a = noise_equivalent_area(as_float_array(psf_sigma_px, "psf_sigma_px")) * (
        as_float_array(background_e, "background_e") + as_float_array(read_noise_e, "read_noise_e") ** 2)
    return 0.5 * (s2 + np.sqrt(s2 * s2 + 4.0 * s2 * a))


def _pixel_terms(offset: NDArray, sigma: NDArray, radius: int) -> tuple[NDArray, ...]:
    """Per pixel of a 1-D stamp: fraction g, dg/dx and dg/ds; arrays of shape (N, 2r + 1).

    ``offset`` (N,) is the star's position relative to the stamp's central pixel.
    """
    edges = np.arange(-radius - 0.5, radius + 1.0)[None, :]
    u = (edges - offset[:, None]) / sigma[:, None]  # (N, S + 1) standardised pixel edges
    cdf = 0.5 * (1.0 + erf(u / _SQRT2))
    pdf = _INV_SQRT_2PI * np.exp(-0.5 * u * u)
    g = np.diff(cdf, axis=1)
    dg_dx = -np.diff(pdf, axis=1) / sigma[:, None]
    dg_ds = -np.diff(pdf * u, axis=1) / sigma[:, None]
    return g, dg_dx, dg_ds


def fisher_information(x_phase_px: ArrayLike, y_phase_px: ArrayLike, flux_e: ArrayLike,
                       psf_sigma_px: ArrayLike, background_e: ArrayLike = 0.0,
                       read_noise_e: ArrayLike = 0.0, *, fit_sigma: bool = False
                       ) -> NDArray[np.float64]:
    """Fisher information matrix of (x, y, F, B[, s]) for N star images (module docstring).

    Parameters
    ----------
    x_phase_px, y_phase_px : array_like, shape (N,) or scalar
        Star position relative to the centre of its pixel (only the sub-pixel phase matters).
    flux_e, psf_sigma_px, background_e, read_noise_e : array_like, shape (N,) or scalar
        Star electrons, Gaussian PSF standard deviation (px), background electrons per pixel,
        read noise electrons rms.
    fit_sigma : bool
        Include the PSF width as a fifth parameter.

    Returns
    -------
    ndarray, shape (N, P, P)
        N = the size of the inputs' broadcast (flattened); P = 4, or 5 with ``fit_sigma``.
    """
    xp, yp, f, s, b, r = (a.ravel() for a in np.broadcast_arrays(*(
        np.atleast_1d(np.asarray(v, dtype=float)) for v in (
            x_phase_px, y_phase_px, flux_e, psf_sigma_px, background_e, read_noise_e))))
    if not (np.all(np.isfinite(s)) and np.all(s > 0)):
        raise InvalidInputError("psf_sigma_px must be positive and finite")
    if np.any(f <= 0) or np.any(b < 0) or np.any(r < 0) or not np.all(np.isfinite(f + b + r)):
        raise InvalidInputError("flux_e must be > 0; background_e and read_noise_e must be >= 0")
    radius = int(np.ceil(STAMP_SIGMAS * s.max())) + 1
    gx, dgx, dsx = _pixel_terms(xp, s, radius)
    gy, dgy, dsy = _pixel_terms(yp, s, radius)
    outer = np.einsum  # (N, S, S) images: [n, j, i] = row j (y), column i (x)
    derivs = [f[:, None, None] * outer("ni,nj->nji", dgx, gy),
              f[:, None, None] * outer("ni,nj->nji", gx, dgy),
              outer("ni,nj->nji", gx, gy),
              np.ones_like(gx[:, None, :] * gy[:, :, None])]
    if fit_sigma:
        derivs.append(f[:, None, None] * (outer("ni,nj->nji", dsx, gy)
                                          + outer("ni,nj->nji", gx, dsy)))
    mean = f[:, None, None] * derivs[2] + b[:, None, None]
    inv_var = 1.0 / (mean + r[:, None, None] ** 2)
    d = np.stack(derivs, axis=1).reshape(len(f), len(derivs), -1)  # (N, P, S*S)
    return np.einsum("npm,nqm,nm->npq", d, d, inv_var.reshape(len(f), -1))


def crb_sigma_px(flux_e: ArrayLike, psf_sigma_px: ArrayLike, background_e: ArrayLike = 0.0,
                 read_noise_e: ArrayLike = 0.0, *, x_phase_px: ArrayLike = 0.0,
                 y_phase_px: ArrayLike = 0.0, nuisance: bool = True, fit_sigma: bool = False
                 ) -> NDArray[np.float64]:
    """Cramér-Rao lower bound on the 1-sigma error of a star's x centroid, in pixels.

    Parameters
    ----------
    flux_e : array_like
        Star electrons (> 0).
    psf_sigma_px : array_like
        Gaussian PSF standard deviation, px.
    background_e, read_noise_e : array_like
        Sky + dark electrons per pixel, and read noise electrons rms per pixel.
    x_phase_px, y_phase_px : array_like
        Sub-pixel position (the bound depends on it slightly for narrow PSFs).
    nuisance : bool
        With flux and background unknown too (default); False: only x, y unknown.
    fit_sigma : bool
        With the PSF width unknown too.

    Returns
    -------
    ndarray
        The bound for every broadcast combination of the inputs (shape of the broadcast).
    """
    shape = np.broadcast_shapes(*(np.shape(v) for v in (
        flux_e, psf_sigma_px, background_e, read_noise_e, x_phase_px, y_phase_px)))
    info = fisher_information(x_phase_px, y_phase_px, flux_e, psf_sigma_px, background_e,
                              read_noise_e, fit_sigma=fit_sigma)
    if not nuisance:
        info = info[:, :2, :2]
    cov = np.linalg.inv(info)
    return np.sqrt(cov[:, 0, 0]).reshape(shape)


def crb_background_limited_px(flux_e: ArrayLike, psf_sigma_px: ArrayLike,
                              noise_e: ArrayLike) -> NDArray[np.float64]:
    """Closed-form background-limited bound ``sqrt(8 pi) s^2 sigma_N / F`` (continuous
    Gaussian, per-pixel noise ``noise_e`` rms, flux and background known)."""
    s = np.asarray(psf_sigma_px, dtype=float)
    return math.sqrt(8.0 * math.pi) * s * s * np.asarray(noise_e, dtype=float) / np.asarray(
        flux_e, dtype=float)


def crb_photon_limited_px(flux_e: ArrayLike, psf_sigma_px: ArrayLike) -> NDArray[np.float64]:
    """Closed-form photon-limited bound ``s / sqrt(F)`` (continuous Gaussian, no background)."""
    return np.asarray(psf_sigma_px, dtype=float) / np.sqrt(np.asarray(flux_e, dtype=float))
