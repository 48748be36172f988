"""Objects that move unlike the stars: the three RSO indicators of Sease 2013 chapter 4.

Sease 2013 ch. 4 "RSO Indicators", eqs. 4.11-4.15 (Sease 2013 Ch.4 Eq. 4.11–4.15). Every star streak
of one image is the same rotation seen at a different place; a resident space object (RSO), an
overlapping pair or a corrupted streak is not. Per streak, from the camera vectors r_i and b_i
of its two ends:

(a) **centre of rotation**: how far the common centre of rotation is from the streak's
    bisector, ``a . n_i`` with ``n_i = (b_i - r_i) / |b_i - r_i|`` (rad);
(b) **angular displacement**: the angle the streak turns through about the centre of rotation,
    ``phi_i = angle(r_i - (r_i . a) a, b_i - (b_i . a) a)`` (rad);
(c) **combined**: the OLAE residual of the catalog-free rate (:mod:`._catalog_free`), which
    captures axis and angle together.

The seed works in the image plane, with the centre of rotation X the point where the streaks'
perpendicular bisectors meet, ``V_i = p_i - X`` and, when the streaks are parallel (X at
infinity), the slope and length of each streak instead. Here the same quantities are taken on
the unit sphere, where the centre of rotation is the spin axis ``a`` (X is its image): both ends
of a star's path are equally far from ``a``, so the plane bisecting them (normal ``n_i``)
contains ``a``, and every star turns through the same angle about it. This is exact for any
axis direction and any field: no switch to slopes and lengths, and no false outliers from the
projection, which in the image plane makes streaks near the corners of a 23-degree field up to
5 % longer than at the centre and tilts them by up to 2.4 degrees (the cause of most of the false
flags of the image-plane forms). ``a`` is fitted from the streaks alone (least median of
squares over the pairs ``n_i x n_j``, then least squares on the streaks within
:data:`INLIER_Z` robust sigmas).

Decision (seed: ``|x - mean| > k sigma``, k = 2.5): a streak is flagged when
``|x_i - median| / max(1.4826 MAD, sigma_i) > k``, where ``sigma_i`` is the scatter that
streak's endpoint covariance predicts for the indicator (propagated below); this per-streak
floor is the seed's "lower bound on the variance" (Sease 2013 Ch.4 Eq. 4.11–4.15), which it characterises on
RSO-free images. The end precision used is at least :data:`ENDPOINT_FLOOR_PX`.

A streak with an end within ``edge_margin_px`` of the image border may be cut by it: its end
is where the star left the field, not where it was at the end of the exposure. The bisector of
a piece of a star's path still contains the spin axis, so indicator (a) still applies; (b) and
(c) do not, and are NaN (never flagged) for such streaks (``truncated``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import Camera
from ..errors import InvalidInputError
from ._catalog_free import K_SIGMA

IndicatorName = Literal["centre_of_rotation", "angular_displacement", "combined"]
"""The three indicators (module docstring: (a), (b) and their combination)."""
INDICATORS: tuple[IndicatorName, ...] = get_args(IndicatorName)
"""The names of :data:`IndicatorName`, in its order: the keys of :class:`RsoIndicators`' maps."""
ENDPOINT_FLOOR_PX = 0.1
"""Smallest end precision (1 sigma, px) the indicators assume. The segment fit's sigma of a
bright streak counts photon noise only and falls under the true end error against the
simulator's truth on RSO-free frames of the Table 4.4 campaign (docs/attitude_and_rate.md gives
both), and 0.1 px is the accuracy limit of centroiding in Samaan 2002. Below it, the k-sigma rule would
flag the tail of the stars' own scatter."""
EDGE_MARGIN_PX = 4.0
"""An end closer than this to the image border may be cut by it (3 sigma of a 1-px PSF and the
inward pull of the corner detectors, docs/attitude_and_rate.md's bias calibration)."""
INLIER_Z = 3.0
"""Streaks whose bisectors miss the first spin axis by more than this many robust sigmas are
left out of its least-squares refit."""
AXIS_PAIRS_FROM = 30
"""The spin axis is first sought among the pairs of the first (brightest) streaks up to this
many."""


@dataclass(frozen=True)
class RsoIndicators:
    """Indicator values, z-scores and flags per streak (N,) for the three indicators.

    ``values``, ``z`` and ``flags`` map each name of :data:`INDICATORS` to an (N,) array (rad;
    the combined one in OLAE residual units, ~rad); ``axis`` (3,) is the spin axis fitted from
    the bisectors (camera frame, unit; the centre of rotation on the sphere); ``truncated``
    (N,) marks the streaks that may be cut by the image border (no displacement or combined
    value). ``candidates`` are the streak indices flagged by the combined indicator.
    """

    values: dict[IndicatorName, NDArray[np.float64]]
    z: dict[IndicatorName, NDArray[np.float64]]
    flags: dict[IndicatorName, NDArray[np.bool_]]
    axis: NDArray[np.float64]
    truncated: NDArray[np.bool_]

    @property
    def candidates(self) -> NDArray[np.intp]:
        return np.flatnonzero(self.flags["combined"])


def _unit(v: NDArray) -> NDArray[np.float64]:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def spin_axis(vectors_a: ArrayLike, vectors_b: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Spin axis (3,) from the bisector planes of N >= 2 streaks, and each one's offset ``a . n_i``.

    ``vectors_a``, ``vectors_b`` (N, 3) are the camera vectors of each streak's ends; the axis
    is the direction closest to every bisector plane (normal ``n_i``, module docstring), taken
    first as the pair ``n_i x n_j`` with the least median offset, then refitted (smallest
    eigenvector of ``sum n n^T``) twice on the streaks within :data:`INLIER_Z` robust sigmas of
    it. Its sign is that of the apparent rotation from the a ends to the b ends of most streaks
    (when the a ends are the starts, the camera's rate is along ``-axis``).
    """
    a, b = _unit(np.asarray(vectors_a, dtype=float)), _unit(np.asarray(vectors_b, dtype=float))
    chords = b - a
    if np.any(np.linalg.norm(chords, axis=1) == 0.0):
        raise InvalidInputError("every streak's two ends must differ")
    normals = _unit(chords)
    first, second = np.triu_indices(min(len(normals), AXIS_PAIRS_FROM), k=1)
    trials = np.cross(normals[first], normals[second])
    trials = trials[np.linalg.norm(trials, axis=1) > 1e-12]
    if len(trials) == 0:
        raise InvalidInputError("need two streaks that are not along the same great circle")
    trials = _unit(trials)
    axis = trials[np.argmin(np.median(np.abs(trials @ normals.T), axis=1))]
    for _ in range(2):
        offset = normals @ axis
        inliers = np.abs(offset) <= INLIER_Z * 1.4826 * float(np.median(np.abs(offset)))
        if inliers.sum() >= 2:
            axis = np.linalg.eigh(normals[inliers].T @ normals[inliers])[1][:, 0]
    turning = np.einsum("ij,j->i", np.cross(a, b), axis)
    axis = axis if np.median(turning) >= 0 else -axis
    return axis, normals @ axis


def turn_angles(vectors_a: ArrayLike, vectors_b: ArrayLike, axis: ArrayLike) -> NDArray[np.float64]:
    """Unsigned angles (N,) through which each streak's ends (N, 3) turn about ``axis`` (3,)."""
    a, b, w = np.asarray(vectors_a, float), np.asarray(vectors_b, float), _unit(np.asarray(axis, float))
    a_perp, b_perp = a - np.outer(a @ w, w), b - np.outer(b @ w, w)
    return np.arctan2(np.linalg.norm(np.cross(a_perp, b_perp), axis=1), np.sum(a_perp * b_perp, axis=1))


def expected_scatter(vectors_a: ArrayLike, vectors_b: ArrayLike, axis: ArrayLike,
                     sigma_rad: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Predicted 1-sigma scatter (N,) of the three indicators from each end's precision (rad).

    With each end off by ``sigma`` (per axis, tangent to the sphere) and ``rho = |a x v|`` an
    end's distance from the axis: centre of rotation ``sigma sqrt(rho_a^2 + rho_b^2) / |b - a|``
    (the end errors across the bisector, over the chord); displacement ``sigma sqrt(1 /
    rho_a^2 + 1 / rho_b^2)`` (the errors along the path, over the radius: stars near the axis
    turn through a poorly measured angle); combined ``2 sqrt(2) sigma`` (the misfit of the two
    ends, twice the Rayleigh scale as in :func:`.catalog_free.catalog_free_rate`'s floor).
    """
    a, b, w = np.asarray(vectors_a, float), np.asarray(vectors_b, float), _unit(np.asarray(axis, float))
    sigma = np.broadcast_to(np.asarray(sigma_rad, dtype=float), (len(a),))
    rho_a, rho_b = np.linalg.norm(np.cross(a, w), axis=1), np.linalg.norm(np.cross(b, w), axis=1)
    chord = np.linalg.norm(b - a, axis=1)
    cor = sigma * np.hypot(rho_a, rho_b) / chord
    with np.errstate(divide="ignore"):
        displacement = sigma * np.sqrt(1.0 / rho_a**2 + 1.0 / rho_b**2)
    return cor, displacement, 2.0 * np.sqrt(2.0) * sigma


def indicator_z(values: ArrayLike, sigma: ArrayLike) -> NDArray[np.float64]:
    """``(x_i - median) / max(1.4826 MAD, sigma_i)`` (N,) over the finite values (NaN elsewhere)."""
    x = np.asarray(values, dtype=float)
    if not np.any(np.isfinite(x)):
        return np.full(x.shape, np.nan)
    centre = np.nanmedian(x)
    spread = 1.4826 * float(np.nanmedian(np.abs(x - centre)))
    return (x - centre) / np.maximum(spread, np.asarray(sigma, dtype=float))


def truncated_streaks(first_xy: ArrayLike, second_xy: ArrayLike, camera: Camera,
                      margin_px: float = EDGE_MARGIN_PX) -> NDArray[np.bool_]:
    """Streaks (N,) with an end (N, 2) within ``margin_px`` of the image border."""
    p1, p2 = np.asarray(first_xy, dtype=float), np.asarray(second_xy, dtype=float)
    inside = camera.in_image(p1[:, 0], p1[:, 1], margin_px) & camera.in_image(p2[:, 0], p2[:, 1], margin_px)
    return ~inside


def rso_indicators(
    first_xy: ArrayLike,
    second_xy: ArrayLike,
    camera: Camera,
    olae_residuals: ArrayLike,
    *,
    k_sigma: float = K_SIGMA,
    endpoint_sigma_px: ArrayLike = 0.3,
    min_endpoint_sigma_px: float = ENDPOINT_FLOOR_PX,
    edge_margin_px: float = EDGE_MARGIN_PX,
) -> RsoIndicators:
    """The three indicators of N >= 2 streaks (ends (N, 2) each, px) seen by ``camera``.

    ``olae_residuals`` (N,) are the catalog-free rate's residuals for the same streaks (the ends
    in the same order); ``endpoint_sigma_px`` (scalar or (N,)) each streak's end precision
    (1 sigma, px), taken at least ``min_endpoint_sigma_px``; a streak is flagged by an indicator
    when its z-score exceeds ``k_sigma`` (module docstring).
    """
    p1, p2 = np.asarray(first_xy, dtype=float), np.asarray(second_xy, dtype=float)
    if p1.shape != p2.shape or p1.ndim != 2 or p1.shape[1] != 2 or len(p1) < 2:
        raise InvalidInputError(f"streak ends must be two (N, 2) arrays with N >= 2, got {p1.shape}, {p2.shape}")
    va, vb = camera.pixel_to_vector(p1[:, 0], p1[:, 1]), camera.pixel_to_vector(p2[:, 0], p2[:, 1])
    sigma = np.maximum(np.broadcast_to(np.asarray(endpoint_sigma_px, dtype=float), (len(p1),)),
                       min_endpoint_sigma_px) / camera.fx
    truncated = truncated_streaks(p1, p2, camera, edge_margin_px)
    axis, offsets = spin_axis(va, vb)
    sigma_cor, sigma_turn, sigma_combined = expected_scatter(va, vb, axis, sigma)
    values: dict[IndicatorName, NDArray[np.float64]] = {
        "centre_of_rotation": offsets,
        "angular_displacement": np.where(truncated, np.nan, turn_angles(va, vb, axis)),
        "combined": np.where(truncated, np.nan, np.asarray(olae_residuals, dtype=float)),
    }
    scatter = dict(zip(INDICATORS, (sigma_cor, sigma_turn, sigma_combined), strict=True))
    z = {name: indicator_z(values[name], scatter[name]) for name in INDICATORS}
    flags = {name: np.nan_to_num(np.abs(z[name]), nan=0.0) > k_sigma for name in INDICATORS}
    return RsoIndicators(values, z, flags, axis, truncated)
