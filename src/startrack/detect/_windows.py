"""Square pixel windows around given positions, and the per-window results of a centroider.

Windowed centroiders (:mod:`._centroid_windowed`, :mod:`._centroid_mle`) and the predictive pass
(:mod:`._predictive`, Samaan 2002 Eq. 1–3 step 4) all work on an (N, S, S)
stack of windows cut from the image: ``values[n, j, i]`` is pixel ``(x0[n] + i, y0[n] + j)``.
Pixels beyond the image border or flagged invalid are NaN, so every reduction over a window
ignores them the same way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

from ._compiled import kernels


@dataclass(frozen=True)
class Windows:
    """N square windows of side S = 2 * half + 1.

    Attributes
    ----------
    values : ndarray, shape (N, S, S), float64
        Pixel values in the image's units; NaN outside the image or where invalid.
    x0, y0 : ndarray of int, shape (N,)
        Column and row of each window's first pixel (may be negative at the border).
    """

    values: NDArray[np.float64]
    x0: NDArray[np.int64]
    y0: NDArray[np.int64]

    def __len__(self) -> int:
        return int(self.x0.size)

    @property
    def half(self) -> int:
        return self.values.shape[1] // 2

    def coords(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pixel-centre coordinates (x, y) of every window pixel, each of shape (N, 1, S) and
        (N, S, 1) (broadcast against ``values``)."""
        k = np.arange(self.values.shape[1], dtype=np.float64)
        return ((self.x0[:, None] + k)[:, None, :].astype(np.float64),
                (self.y0[:, None] + k)[:, :, None].astype(np.float64))

    def take(self, index) -> Windows:
        """A subset or reordering of the windows, by index array or boolean mask."""
        return Windows(self.values[index], self.x0[index], self.y0[index])

    def border(self) -> NDArray[np.float64]:
        """The values of each window's outer ring of pixels, shape (N, 4S - 4) (NaN included)."""
        v = self.values
        return np.concatenate([v[:, 0, :], v[:, -1, :], v[:, 1:-1, 0], v[:, 1:-1, -1]], axis=1)


def separable_moments(q: NDArray, wx: NDArray, dx: NDArray, wy: NDArray, dy: NDArray) -> NDArray:
    """Weighted moments of windows under separable weights,
    ``M[..., a, b] = sum_j sum_i wy[n, j] dy[n, j]^a q[..., n, j, i] wx[n, i] dx[n, i]^b``.

    Parameters
    ----------
    q : ndarray, shape (..., N, S, S)
        Window values (one or more stacks of N windows).
    wx, dx, wy, dy : ndarray, shape (N, S)
        Per-axis weights and coordinates (columns for x, rows for y).

    Returns
    -------
    ndarray, shape (..., N, 3, 3)
        Moments for a, b in 0, 1, 2, float64: one compiled loop
        (:func:`.frame_kernels.separable_moments`), the sum along x first, which is what makes
        per-window sums cheap on small windows.
    """
    q = np.asarray(q, dtype=np.float64)
    lead, (n, s) = q.shape[:-3], q.shape[-3:-1]
    if q.size == 0:
        return np.zeros((*lead, n, 3, 3))
    plain = [np.ascontiguousarray(a, dtype=np.float64) for a in (wx, dx, wy, dy)]
    out = kernels().separable_moments(np.ascontiguousarray(q).reshape(-1, n, s, s), *plain)
    return out.reshape(*lead, n, 3, 3)


def fast_median(values: NDArray) -> NDArray:
    """Median along the last axis of NaN-free ``values`` (non-empty): ``np.median``'s value
    from one ``np.partition``, without its overhead on small arrays."""
    n = values.shape[-1]
    mid = n // 2
    if n % 2:
        return np.partition(values, mid, axis=-1)[..., mid]
    part = np.partition(values, (mid - 1, mid), axis=-1)
    return (part[..., mid - 1] + part[..., mid]) / 2.0


def fast_quantile(values: NDArray, q: float) -> float:
    """Quantile ``q`` (in [0, 1]) of the 1-D NaN-free non-empty ``values``: ``np.quantile``'s
    value (its default, linear method, with its interpolation rule) from one ``np.partition``,
    without its overhead on small arrays."""
    n = values.size
    virtual = (n - 1) * q
    if virtual >= n - 1:
        return float(values.max())
    lo = math.floor(virtual)
    part = np.partition(values, (lo, lo + 1))
    a, b = part[lo], part[lo + 1]
    gamma, diff = virtual - lo, b - a
    return float(b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma)


def extract_windows(data: NDArray, cx: NDArray, cy: NDArray, half: int,
                    invalid: NDArray[np.bool_] | None = None) -> Windows:
    """Cut (2 half + 1)-pixel square windows centred on pixels (cx, cy).

    Parameters
    ----------
    data : ndarray, shape (H, W)
        Any numeric dtype.
    cx, cy : array_like of int, shape (N,)
        Central pixel (column, row) of each window.
    half : int >= 1
        Half-width in pixels.
    invalid : ndarray of bool, shape (H, W), optional
        Pixels to set to NaN.

    Returns
    -------
    Windows
        One compiled loop (:func:`.frame_kernels.extract_windows`).
    """
    cx = np.ascontiguousarray(cx, dtype=np.int64)
    cy = np.ascontiguousarray(cy, dtype=np.int64)
    none = np.zeros((0, 0), dtype=np.bool_)
    values = kernels().extract_windows(data, cx, cy, int(half), none if invalid is None else invalid)
    return Windows(values, cx - half, cy - half)


@dataclass(frozen=True)
class Centroids:
    """What a centroider returns for N spots, all arrays of shape (N,).

    Attributes
    ----------
    x, y : float
        Centroid in our pixel convention (0-based pixel centres).
    flux : float
        Star signal (image units); NaN when the method does not measure it (the spot's summed
        flux is used then).
    sigma_px : float
        The method's own 1-sigma error per axis, px: propagated noise, or the fit covariance.
    psf_sigma_px : float
        The PSF standard deviation the method fitted or used (NaN when none).
    ok : bool
        False where the method failed (no signal, fit diverged): the caller falls back.
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    flux: NDArray[np.float64]
    sigma_px: NDArray[np.float64]
    psf_sigma_px: NDArray[np.float64]
    ok: NDArray[np.bool_]

    def take(self, index) -> Centroids:
        """A subset or reordering, by index array or boolean mask."""
        return Centroids(**{f.name: getattr(self, f.name)[index] for f in fields(self)})

    def with_rows(self, index: NDArray[np.intp], part: Centroids) -> Centroids:
        """This result with the rows ``index`` (shape (K,)) replaced by ``part`` (K rows)."""
        out = {}
        for f in fields(self):
            values = getattr(self, f.name).copy()
            values[index] = getattr(part, f.name)
            out[f.name] = values
        return Centroids(**out)

    def where(self, use: NDArray[np.bool_], other: Centroids) -> Centroids:
        """Element-wise: this result where ``use``, ``other`` elsewhere."""
        return Centroids(**{f.name: np.where(use, getattr(self, f.name), getattr(other, f.name))
                            for f in fields(self)})
