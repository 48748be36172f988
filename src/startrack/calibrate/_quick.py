"""Jacobs 1995's quick calibration methods (Ch. 6; Jacobs 1995 §6.2.1, App F.2, §6.2.2).

- **Focal length from one star pair** (§6.2.2, ``Estf.mod``): two identified stars at measured
  offsets (u1, v1), (u2, v2) from the optical centre and catalog separation theta satisfy
  ``cos theta = (p + f^2) / sqrt((r1^2 + f^2)(r2^2 + f^2))`` with p = u1 u2 + v1 v2; squared, a
  quadratic in X = f^2 whose positive root is the focal length. Averaged (here: the median) over
  many pairs.
- **Optical centre by rotation** (§6.2.1): a point source imaged while the camera turns about its
  optical axis traces a circle around the principal point; so does every star in a sequence of
  sky images rolled about the boresight. The centre is a linear least-squares circle fit, with a
  common centre and one radius per track.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError, as_float_array, checked_number
from ..frames import angle_between


def focal_from_pair(u1: ArrayLike, v1: ArrayLike, u2: ArrayLike, v2: ArrayLike,
                    angle_rad: ArrayLike) -> NDArray[np.float64]:
    """Focal length (px) from star pairs: offsets from the optical centre (px) and true separation.

    Vectorised over pairs; NaN where the quadratic has no positive root (separation 0 or noise).
    """
    u1, v1, u2, v2 = (np.asarray(a, float) for a in (u1, v1, u2, v2))
    inv_cos2 = 1.0 / np.cos(np.asarray(angle_rad, float)) ** 2
    p = u1 * u2 + v1 * v2
    r1, r2 = u1 * u1 + v1 * v1, u2 * u2 + v2 * v2
    a = inv_cos2 - 1.0
    b = 2.0 * p * inv_cos2 - (r1 + r2)
    c = p * p * inv_cos2 - r1 * r2
    with np.errstate(invalid="ignore", divide="ignore"):
        x = (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
        return np.where(x > 0, np.sqrt(x), np.nan)


def focal_from_stars(x: ArrayLike, y: ArrayLike, vectors: ArrayLike, cx: float, cy: float,
                     min_separation_px: float = 20.0) -> tuple[float, float]:
    """Median single-pair focal length (px) over all pairs of identified stars, and the robust
    spread (1.4826 MAD) of the pair estimates.

    Parameters
    ----------
    x, y : array_like, shape (K,)
        Measured positions, px.
    vectors : array_like, shape (K, 3)
        Catalog directions of the same stars (any frame).
    cx, cy : float
        Optical centre, px.
    min_separation_px : float
        Pairs closer than this on the image are skipped (their angle is mostly centroid noise).
    """
    cx, cy = checked_number(cx, "cx"), checked_number(cy, "cy")
    min_separation_px = checked_number(min_separation_px, "min_separation_px", low=0.0)
    xs, ys = as_float_array(x, "x") - cx, as_float_array(y, "y") - cy
    vecs = as_float_array(vectors, "vectors")
    if xs.ndim != 1 or ys.shape != xs.shape or vecs.shape != (xs.size, 3):
        raise InvalidInputError(f"x and y must be (K,) and vectors (K, 3), got shapes {xs.shape}, {ys.shape}, "
                                f"{vecs.shape}")
    if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys)) and np.all(np.isfinite(vecs))):
        raise InvalidInputError("x, y and vectors must be finite")
    i, j = np.triu_indices(xs.size, k=1)
    keep = np.hypot(xs[i] - xs[j], ys[i] - ys[j]) >= min_separation_px
    i, j = i[keep], j[keep]
    if i.size == 0:
        raise InvalidInputError(f"need at least two stars {min_separation_px} px apart, got {xs.size} stars")
    f = focal_from_pair(xs[i], ys[i], xs[j], ys[j], angle_between(vecs[i], vecs[j]))
    f = f[np.isfinite(f)]
    med = float(np.median(f))
    return med, float(1.4826 * np.median(np.abs(f - med)))


def centre_from_rotation(tracks: Sequence[tuple[ArrayLike, ArrayLike]]) -> tuple[float, float, NDArray]:
    """Principal point from point tracks recorded while the camera rolls about its optical axis.

    Each track (x, y) is one source's positions over the roll sequence; all circles share the
    centre (cx, cy). Solves ``x^2 + y^2 = 2 cx x + 2 cy y + d_k`` by linear least squares
    (d_k = r_k^2 - cx^2 - cy^2 per track).

    Returns
    -------
    cx, cy : float
    radii : ndarray, shape (n_tracks,)
    """
    rows, rhs = [], []
    n = len(tracks)
    for k, (tx, ty) in enumerate(tracks):
        tx, ty = np.asarray(tx, float), np.asarray(ty, float)
        block = np.zeros((tx.size, 2 + n))
        block[:, 0], block[:, 1], block[:, 2 + k] = 2 * tx, 2 * ty, 1.0
        rows.append(block)
        rhs.append(tx * tx + ty * ty)
    design = np.concatenate(rows)
    if n == 0 or design.shape[0] < 2 + n + 1:
        raise InvalidInputError("need at least one track with three or more positions (more for more tracks)")
    sol, *_ = np.linalg.lstsq(design, np.concatenate(rhs), rcond=None)
    cx, cy = float(sol[0]), float(sol[1])
    radii = np.sqrt(np.maximum(sol[2:] + cx * cx + cy * cy, 0.0))
    return cx, cy, radii


def focal_sensitivity(u1, v1, u2, v2, f_true: float, f_used: float) -> float:
    """Angular error (rad) of a pair's separation measured with the wrong focal length
    (Jacobs 1995 §6.1; the angle with f_used minus the angle with f_true)."""
    def angle(f):
        a = np.array([u1, v1, f])
        b = np.array([u2, v2, f])
        return math.atan2(np.linalg.norm(np.cross(a, b)), float(a @ b))

    return angle(f_used) - angle(f_true)
