"""Light of moving point sources integrated over the exposure: points, streaks, rolling shutter.

A source that moves during the exposure leaves the time integral of its PSF along its path
(Sease 2013 §"Streaking Dynamics", Samaan 2002 "The Effect of Image Smear": the total light is
conserved, its footprint grows). We split the time a source is exposed into n sub-intervals,
place the PSF at the source's position at the middle of each (the midpoint rule; the seed's
fencepost erratum, Sease 2013 Eq. 2.12, is avoided) and give it the share of the light
that falls in that sub-interval. n is chosen so that the source moves at most ``substep_px``
between samples (0.25 px by default): with the PSF integrated over pixels the streak then has no
gaps or ripples; at zero rate n = 1 and the image is the point-source image.

The pixel-integrated Gaussian is separable, so source i's streak in its window is a product of
two small matrices, ``sum_s w_s fy_s(row) fx_s(col) = (FY^T W) @ FX`` (FY: n x rows, FX:
n x columns, the 1-D pixel fractions of every sample); the weights W may depend on the row (a
rolling shutter). The Airy PSF is not separable and is drawn sample by sample.

Rolling shutter: row y integrates from ``start_s + y * line_time_s`` for ``exposure_s``; a
sample covering the times [t_lo, t_hi] gives row y the fraction
``overlap([t_lo, t_hi], row window) / exposure_s`` of the source's light (with a global shutter,
``(t_hi - t_lo) / exposure_s`` for every row).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.special import erf

from . import _checks
from ._optics import airy_stamps

CHUNK_ELEMENTS = 4_000_000
"""Largest intermediate array (samples x window pixels) built at once."""
_SQRT2 = math.sqrt(2.0)
_SCATTER_BINCOUNT_MIN = 50_000


@dataclass(frozen=True)
class Shutter:
    """When each row integrates light: from ``start_s + y * line_time_s`` for ``exposure_s``.

    ``line_time_s`` = 0 is a global shutter (every row from ``start_s``).
    """

    start_s: float
    exposure_s: float
    line_time_s: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "start_s", float(self.start_s))
        object.__setattr__(self, "exposure_s", _checks.positive("exposure_s", self.exposure_s))
        line = _checks.positive("line_time_s", self.line_time_s, allow_zero=True)
        object.__setattr__(self, "line_time_s", line)

    @property
    def rolling(self) -> bool:
        return self.line_time_s > 0

    def row_start_s(self, y: NDArray) -> NDArray[np.float64]:
        """Start of the integration of the row at ``y`` (fractional rows allowed)."""
        return self.start_s + np.asarray(y, dtype=float) * self.line_time_s

    def mid_s(self, height: int) -> float:
        """Middle of the frame's integration: mid-exposure of the middle row."""
        return self.start_s + 0.5 * self.exposure_s + 0.5 * (height - 1) * self.line_time_s


@dataclass(frozen=True)
class Samples:
    """Positions of N sources at n sub-interval midpoints, and the sub-intervals (s).

    All arrays have shape (N, n); ``x, y`` in our pixel convention.
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    t_lo: NDArray[np.float64]
    t_hi: NDArray[np.float64]


def sub_intervals(t_start: NDArray, t_end: NDArray, n: int) -> tuple[NDArray, NDArray, NDArray]:
    """n equal sub-intervals of [t_start_i, t_end_i] per source: (lo, mid, hi), each (N, n)."""
    frac = np.arange(n + 1) / n
    edges = t_start[:, None] + (t_end - t_start)[:, None] * frac[None, :]
    return edges[:, :-1], 0.5 * (edges[:, :-1] + edges[:, 1:]), edges[:, 1:]


def substeps(path_length_px: float, substep_px: float) -> int:
    """Sub-intervals needed so a source moves at most ``substep_px`` in one (at least 1)."""
    return max(1, math.ceil(path_length_px / substep_px - 1e-9))


def path_length_px(x: NDArray, y: NDArray) -> NDArray[np.float64]:
    """Length of polylines (N, m) in pixels (NaN samples count as 0)."""
    return np.nansum(np.hypot(np.diff(x, axis=1), np.diff(y, axis=1)), axis=1)


def row_weights(samples: Samples, rows: NDArray, shutter: Shutter) -> NDArray[np.float64]:
    """Share of each source's light given by each sample to each row.

    ``rows`` is (N, R) (the same rows for every sample of a source) or (N, n, R); the result is
    (N, n, R), or (N, n, 1) with a global shutter (the same share for every row).
    """
    if not shutter.rolling:
        return ((samples.t_hi - samples.t_lo) / shutter.exposure_s)[:, :, None]
    row_lo = shutter.row_start_s(rows)
    if row_lo.ndim == 2:
        row_lo = row_lo[:, None, :]
    lo = np.maximum(samples.t_lo[:, :, None], row_lo)
    hi = np.minimum(samples.t_hi[:, :, None], row_lo + shutter.exposure_s)
    return np.maximum(hi - lo, 0.0) / shutter.exposure_s


def window_fractions(pos: NDArray, origin: NDArray, size: int, sigma: NDArray, radius: int) -> NDArray[np.float64]:
    """1-D pixel fractions of Gaussians at ``pos`` (N, n) in windows of ``size`` pixels starting
    at pixel ``origin`` (N,), sigma (N,): shape (N, n, size).

    Each sample's light is computed only over the ``2 radius + 1`` pixels around its nearest pixel
    (its stamp) and placed into the window; the rest of the window row is 0.
    """
    near = np.floor(pos + 0.5).astype(np.intp)
    offset = near - radius - origin[:, None]  # first stamp pixel, in window pixels
    local = np.arange(-radius - 0.5, radius + 1.0)[None, None, :]  # stamp pixel edges
    scale = (1.0 / (_SQRT2 * sigma))[:, None, None]
    fractions = 0.5 * np.diff(erf((local - (pos - near)[:, :, None]) * scale), axis=2)
    if size == 2 * radius + 1 and not offset.any():
        return fractions
    out = np.zeros(pos.shape + (size,))
    np.put_along_axis(out, offset[:, :, None] + np.arange(2 * radius + 1)[None, None, :], fractions, axis=2)
    return out


def _windows(x: NDArray, y: NDArray, radius: int) -> tuple[NDArray, NDArray, int, int]:
    """Origins (N,) and common sizes of the windows that hold every sample's stamp."""
    xr = np.floor(x + 0.5).astype(np.intp)
    yr = np.floor(y + 0.5).astype(np.intp)
    x0 = xr.min(axis=1) - radius
    y0 = yr.min(axis=1) - radius
    width = int((xr.max(axis=1) + radius - x0).max()) + 1
    height = int((yr.max(axis=1) + radius - y0).max()) + 1
    return x0, y0, width, height


def add_gaussian_paths(image: NDArray[np.float64], samples: Samples, flux: NDArray, sigma: NDArray,
                       radius: int, shutter: Shutter) -> NDArray[np.float64]:
    """Add the pixel-integrated Gaussian streaks of N sources into ``image`` (in place).

    ``flux`` (N,) is each source's light over its whole exposure, ``sigma`` (N,) its PSF width,
    ``radius`` the stamp half-width (px) around each sample.
    """
    n_src, n_samp = samples.x.shape
    if n_src == 0:
        return image
    x0, y0, width, height = _windows(samples.x, samples.y, radius)
    per_source = n_samp * max(width, height) * 2 + width * height
    step = max(1, CHUNK_ELEMENTS // per_source)
    for lo in range(0, n_src, step):
        part = slice(lo, min(lo + step, n_src))
        sub = Samples(samples.x[part], samples.y[part], samples.t_lo[part], samples.t_hi[part])
        fx = window_fractions(sub.x, x0[part], width, sigma[part], radius)
        fy = window_fractions(sub.y, y0[part], height, sigma[part], radius)
        rows = y0[part, None] + np.arange(height)[None, :]
        fy *= row_weights(sub, rows, shutter) * flux[part, None, None]
        add_windows(image, x0[part], y0[part], np.matmul(np.swapaxes(fy, 1, 2), fx))
    return image


def add_airy_paths(image: NDArray[np.float64], samples: Samples, flux: NDArray, first_zero_px: float,
                   radius: int, shutter: Shutter) -> NDArray[np.float64]:
    """Add pixel-integrated Airy streaks (sample by sample) into ``image`` (in place)."""
    x, y = samples.x.ravel(), samples.y.ravel()
    if x.size == 0:
        return image
    xc = np.floor(x + 0.5).astype(np.intp)
    yc = np.floor(y + 0.5).astype(np.intp)
    rows = yc.reshape(samples.x.shape)[:, :, None] + np.arange(-radius, radius + 1)[None, None, :]
    weights = row_weights(samples, rows, shutter) * flux[:, None, None]
    weights = weights.reshape(x.size, -1)  # (N n, S) or (N n, 1)
    size = 2 * radius + 1
    step = max(1, CHUNK_ELEMENTS // (size * size * 25))
    for lo in range(0, x.size, step):
        part = slice(lo, min(lo + step, x.size))
        stamps = airy_stamps(x[part] - xc[part], y[part] - yc[part], first_zero_px, radius)
        stamps *= weights[part][:, :, None]
        add_windows(image, xc[part] - radius, yc[part] - radius, stamps)
    return image


def add_windows(image: NDArray[np.float64], x0: NDArray, y0: NDArray, stamps: NDArray) -> NDArray[np.float64]:
    """Add (N, Sy, Sx) windows whose top-left pixels are (x0, y0) into ``image``, clipped at edges."""
    if not image.flags.c_contiguous:
        raise ValueError("add_windows needs a C-contiguous image")
    height, width = image.shape
    cols = (x0[:, None] + np.arange(stamps.shape[2]))[:, None, :]
    rows = (y0[:, None] + np.arange(stamps.shape[1]))[:, :, None]
    inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
    rows, cols = np.broadcast_arrays(rows, cols)
    flat = rows[inside] * width + cols[inside]
    values = stamps[inside]
    if values.size >= _SCATTER_BINCOUNT_MIN:
        image += np.bincount(flat, weights=values, minlength=image.size).reshape(image.shape)
    else:
        np.add.at(image.ravel(), flat, values)
    return image
