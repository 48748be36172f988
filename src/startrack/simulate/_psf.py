"""Point-spread function rendering: pixel-integrated Gaussians added into an image.

The PSF is the 2-D Gaussian of Huffman 2006 §3.1 eq. 3.3, integrated
over each pixel's area (the choice consistent with the seed's MLE centroider, eqs. 4.7-4.8). It is
separable, so a pixel's share of a star's light is the product of two 1-D fractions::

    f_x(i) = [erf((i + 0.5 - x) / (sqrt(2) sigma)) - erf((i - 0.5 - x) / (sqrt(2) sigma))] / 2

with pixel i covering [i - 0.5, i + 0.5] (pixel centres at integers, :mod:`startrack.conventions`).

Each star is drawn in a square stamp of half-width ``ceil(radius_sigmas * sigma)`` pixels about
its nearest pixel; the light beyond it (< 1e-6 of the total at the default 5 sigma) is dropped.
All stamps are built as one (N, S, S) array and scatter-added with ``np.add.at``, so there is
no Python loop over stars or pixels. Stamp pixels outside the image are discarded: a star near
the edge loses exactly the light that falls off the detector.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import erf

from ..errors import InvalidInputError
from . import _checks

DEFAULT_RADIUS_SIGMAS: float = 5.0
_SQRT2 = math.sqrt(2.0)


def stamp_radius_px(sigma_px: float, radius_sigmas: float = DEFAULT_RADIUS_SIGMAS) -> int:
    """Half-width in pixels of the stamp drawn for a PSF of width ``sigma_px``."""
    return max(1, math.ceil(radius_sigmas * sigma_px))


def pixel_fractions_1d(offset_px: ArrayLike, sigma_px: ArrayLike,
                       radius_px: int) -> NDArray[np.float64]:
    """Share of a 1-D Gaussian's light in each pixel of a stamp.

    Parameters
    ----------
    offset_px : array_like, shape (N,)
        Position of each star relative to its stamp's central pixel, in pixels.
    sigma_px : array_like, shape (N,) or scalar
        Gaussian standard deviation in pixels.
    radius_px : int
        Half-width of the stamp; it covers pixels -radius_px .. +radius_px.

    Returns
    -------
    ndarray, shape (N, 2 * radius_px + 1)
        Fraction of each star's light falling in each pixel of the stamp.
    """
    offset = np.atleast_1d(np.asarray(offset_px, dtype=float))[:, None]
    scale = 1.0 / (_SQRT2 * np.atleast_1d(np.asarray(sigma_px, dtype=float)))[:, None]
    edges = np.arange(-radius_px - 0.5, radius_px + 1.0)[None, :]  # S + 1 pixel edges
    cdf = erf((edges - offset) * scale)
    return 0.5 * np.diff(cdf, axis=1)


def gaussian_stamps(x: NDArray, y: NDArray, flux: NDArray, sigma_px: NDArray, radius_px: int
                    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """Pixel-integrated Gaussian stamps of N stars.

    Returns
    -------
    x0, y0 : ndarray of int, shape (N,)
        Column and row of each stamp's central pixel (nearest pixel to the star).
    stamps : ndarray, shape (N, S, S), S = 2 * radius_px + 1
        ``stamps[n, j, i]`` is star n's light in pixel (x0 + i - radius_px, y0 + j - radius_px).
    """
    x0 = np.floor(x + 0.5).astype(np.intp)
    y0 = np.floor(y + 0.5).astype(np.intp)
    fx = pixel_fractions_1d(x - x0, sigma_px, radius_px)
    fy = pixel_fractions_1d(y - y0, sigma_px, radius_px)
    stamps = (flux[:, None, None] * fy[:, :, None]) * fx[:, None, :]
    return x0, y0, stamps


def add_stamps(image: NDArray[np.float64], x0: NDArray[np.intp], y0: NDArray[np.intp],
               stamps: NDArray[np.float64]) -> NDArray[np.float64]:
    """Add (N, S, S) stamps centred on pixels (x0, y0) into ``image`` in place, clipped at edges."""
    height, width = image.shape
    radius = stamps.shape[1] // 2
    k = np.arange(-radius, radius + 1)
    cols = (x0[:, None] + k)[:, None, :]  # (N, 1, S)
    rows = (y0[:, None] + k)[:, :, None]  # (N, S, 1)
    inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)  # (N, S, S)
    rows, cols = np.broadcast_arrays(rows, cols)
    np.add.at(image, (rows[inside], cols[inside]), stamps[inside])
    return image


def render_gaussian_psf(shape: tuple[int, int], x: ArrayLike, y: ArrayLike, flux: ArrayLike,
                        sigma_px: ArrayLike, *, radius_sigmas: float = DEFAULT_RADIUS_SIGMAS,
                        out: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """Image of point sources blurred by a pixel-integrated Gaussian PSF.

    Parameters
    ----------
    shape : (height, width)
        Image size in pixels (ignored when ``out`` is given).
    x, y : array_like, shape (N,)
        Source positions in our pixel convention (0-based pixel centres, x = column). Sources
        partly or wholly outside the image are clipped.
    flux : array_like, shape (N,)
        Total light of each source (electrons, or any unit: the image takes the same unit).
    sigma_px : float or array_like, shape (N,)
        Gaussian standard deviation per axis, in pixels, per source or common.
    radius_sigmas : float
        Stamp half-width in units of the largest sigma.
    out : ndarray, shape (height, width), float64, optional
        Image to add into (in place); a new zero image when None.

    Returns
    -------
    ndarray, shape (height, width), float64
        ``out`` (or the new image) with the sources added.
    """
    x = _checks.finite_array("x", x, (None,))
    n = x.shape[0]
    y = _checks.finite_array("y", y, (n,))
    flux = _checks.finite_array("flux", flux, (n,))
    sigma = np.broadcast_to(np.asarray(sigma_px, dtype=float), (n,))
    if n and not (np.all(np.isfinite(sigma)) and np.all(sigma > 0)):
        raise InvalidInputError("sigma_px must be positive and finite")
    image = _output_image(shape, out)
    if n == 0:
        return image
    radius = stamp_radius_px(float(sigma.max()), _checks.positive("radius_sigmas", radius_sigmas))
    return add_stamps(image, *gaussian_stamps(x, y, flux, sigma, radius))


def _output_image(shape: tuple[int, int], out: NDArray[np.float64] | None) -> NDArray[np.float64]:
    if out is not None:
        if not (isinstance(out, np.ndarray) and out.ndim == 2 and out.dtype == np.float64):
            raise InvalidInputError("out must be a 2-D float64 ndarray")
        return out
    if len(shape) != 2 or min(shape) < 1:
        raise InvalidInputError(f"shape must be (height, width) with positive sizes, got {shape!r}")
    return np.zeros((int(shape[0]), int(shape[1])), dtype=np.float64)
