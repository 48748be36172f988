"""Optics across the field: PSF size (field curvature), vignetting, and the Airy PSF.

The lens settings live in :class:`startrack.simulate._radiometry.Optics`; this module turns them
into per-star and per-pixel numbers for a :class:`startrack.camera.Camera`:

- **Off-axis angle** theta of a pixel is the angle between its direction (distortion removed)
  and the boresight; ``r / r_corner`` is the distance from the principal point relative to the
  farthest image corner.
- **Field curvature** (Huffman 2006 §2.3, Table 2.4: a single lens's PSF grows away from the axis):
  ``sigma(r) = sigma_0 * (1 + field_curvature * (r / r_corner)^2)``.
- **Vignetting** (Fowler 2013 Ch.4 §II.A): natural vignetting is the cos^4 law for extended light (the
  sky background per pixel), which for a point source is cos(theta) (the aperture seen obliquely;
  the other cos^3 is the shrinking pixel solid angle, which a star does not feel); mechanical or
  optical fall-off is ``1 - vignetting_edge * (r / r_corner)^2`` and multiplies both.
- **Airy PSF**: the diffraction pattern of a circular aperture with first dark ring at radius r0,
  ``I(r) = pi / (4 w^2) * (2 J1(pi r / w) / (pi r / w))^2`` with ``w = r0 / 1.2197`` (= lambda N /
  pitch), normalised to unit integral over the plane; it is integrated over each pixel by the
  midpoint rule on ``oversample^2`` sub-pixels. Unlike the Gaussian it is not separable, so
  stamps are 2-D; the light outside the stamp (the far rings, a few per cent at 5 r0) is lost,
  as it would fall below the noise.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import j1

from ..camera import Camera
from ._radiometry import Optics

AIRY_FIRST_ZERO = 1.2196698912665045
"""First zero of J1(pi x) / (pi x) in units of lambda N (1.22)."""
AIRY_SIGMA_PER_FIRST_ZERO = 0.42 / AIRY_FIRST_ZERO
"""Best-fit Gaussian sigma of an Airy pattern per first-zero radius (sigma ~ 0.42 lambda N)."""
AIRY_RADIUS_ZEROS = 5.0
"""Half-width of an Airy stamp in first-zero radii."""
AIRY_OVERSAMPLE = 5


def _corner_radius_px(camera: Camera) -> float:
    corners_x = np.array([-0.5, camera.width - 0.5])
    corners_y = np.array([-0.5, camera.height - 0.5])
    return float(np.max(np.hypot(corners_x[:, None] - camera.cx, corners_y[None, :] - camera.cy)))


def relative_radius(camera: Camera, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
    """Distance from the principal point over the distance to the farthest corner (any shape)."""
    return np.hypot(np.asarray(x, dtype=float) - camera.cx,
                    np.asarray(y, dtype=float) - camera.cy) / _corner_radius_px(camera)


def cos_off_axis(camera: Camera, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
    """cos(theta) of pixel positions (any shape): the z component of their unit direction."""
    return camera.pixel_to_vector(x, y)[..., 2]


def psf_sigma_px(camera: Camera, optics: Optics, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
    """Gaussian sigma (px) at pixel positions, with field curvature (shape of ``x``)."""
    r = relative_radius(camera, x, y)
    return optics.psf_sigma_px * (1.0 + optics.field_curvature * r * r)


def star_illumination(camera: Camera, optics: Optics, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
    """Fraction of a star's light that reaches the detector at (x, y), vignetting only (<= 1)."""
    r = relative_radius(camera, x, y)
    factor = 1.0 - optics.vignetting_edge * r * r
    if optics.natural_vignetting:
        factor = factor * cos_off_axis(camera, x, y)
    return factor


def background_illumination(camera: Camera, optics: Optics) -> NDArray[np.float64] | float:
    """Relative sky-background level per pixel, (H, W), or 1.0 when the field is flat.

    cos^4(theta) with natural vignetting (pixel solid angle cos^3 times the oblique aperture),
    times the mechanical fall-off; normalised to 1 on the axis.
    """
    if not optics.natural_vignetting and optics.vignetting_edge == 0.0:
        return 1.0
    ys, xs = np.mgrid[0:camera.height, 0:camera.width].astype(float)
    factor = 1.0 - optics.vignetting_edge * relative_radius(camera, xs, ys) ** 2
    if optics.natural_vignetting:
        factor *= cos_off_axis(camera, xs, ys) ** 4
    return factor


def airy_first_zero_px(optics: Optics) -> float:
    """First dark ring radius (px) of the Airy PSF of ``optics``."""
    if optics.airy_first_zero_px is not None:
        return optics.airy_first_zero_px
    return optics.psf_sigma_px / AIRY_SIGMA_PER_FIRST_ZERO


def airy_stamp_radius_px(first_zero_px: float) -> int:
    """Half-width (px) of the stamps drawn for an Airy PSF."""
    return max(1, math.ceil(AIRY_RADIUS_ZEROS * first_zero_px))


def airy_intensity(r_px: NDArray[np.float64], first_zero_px: float) -> NDArray[np.float64]:
    """Airy PSF per unit area (px^-2) at radius ``r_px``: unit integral over the plane."""
    w = first_zero_px / AIRY_FIRST_ZERO
    u = np.pi * np.asarray(r_px, dtype=float) / w
    with np.errstate(invalid="ignore", divide="ignore"):
        core = np.where(u > 1e-8, 2.0 * j1(u) / u, 1.0)
    return np.pi / (4.0 * w * w) * core * core


def airy_stamps(dx: NDArray, dy: NDArray, first_zero_px: float, radius_px: int,
                oversample: int = AIRY_OVERSAMPLE) -> NDArray[np.float64]:
    """Pixel-integrated Airy stamps of unit flux, shape (N, S, S), S = 2 radius + 1.

    ``dx, dy`` (N,) are the source positions relative to the stamp's central pixel (px). Pixel
    (j, i) of a stamp covers [i - R - 0.5, i - R + 0.5] x [j - R - 0.5, j - R + 0.5].
    """
    k = np.arange(-radius_px, radius_px + 1, dtype=float)
    sub = (np.arange(oversample) + 0.5) / oversample - 0.5
    grid = (k[:, None] + sub[None, :]).ravel()  # (S * os,) sub-pixel centres
    gx = grid[None, :] - np.asarray(dx, dtype=float)[:, None]
    gy = grid[None, :] - np.asarray(dy, dtype=float)[:, None]
    r = np.hypot(gy[:, :, None], gx[:, None, :])  # (N, S os, S os)
    fine = airy_intensity(r, first_zero_px) / (oversample * oversample)
    size = 2 * radius_px + 1
    return fine.reshape(len(gx), size, oversample, size, oversample).sum(axis=(2, 4))
