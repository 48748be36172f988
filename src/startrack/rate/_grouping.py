"""Splitting streak endpoints into the exposure-start and exposure-end sets.

Sease 2013 §3 "Isolating Endpoint Groups", eqs. 3.17-3.19 (Sease 2013 Eq. 3.17–3.19). Both ends
of a streak are equally far from the projected centre of rotation (CoR), so every streak's
perpendicular bisector passes through it; with unit directions ``d_i`` and midpoints ``c_i`` the
CoR X solves ``d_i . X = d_i . c_i`` in the least-squares sense (the seed's printed system eq.
3.18 has an index typo; Sease 2013). Then, with ``V_c = c_i - X`` and ``V_1 = p_i1 - c_i``,
the sign of the z component of ``V_c x V_1`` is the same for all the ends of one exposure time
(eq. 3.19): every streak turns the same way about X.

When the camera axis is perpendicular to the rotation axis the streaks are parallel and X is at
infinity: the fit is then declared parallel (its design matrix nearly rank 1, or X farther than
``max_distance_px`` from the image) and the ends are grouped by the sign of ``(p - c_i) . d``
along the dominant direction d (notes' fallback). Which group is the start is not known from one
image (only simultaneity is); a prior rate sign resolves it (:mod:`._streak_rate`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError

PARALLEL_CONDITION = 0.05
"""Smallest-to-largest singular value ratio of the streak directions below which they count as
parallel (directions spread by less than ~3 degrees: the spin axis within ~20 degrees of the
focal plane for a 20-degree field), where the bisectors fix no usable centre."""


OUTLIER_Z = 3.0
"""Robust z-score beyond which a streak is left out of the second centre-of-rotation fit."""


@dataclass(frozen=True)
class CentreOfRotation:
    """The least-squares centre of rotation of a set of streaks.

    Attributes
    ----------
    xy : ndarray, shape (2,)
        The centre (x, y) in pixels (NaN when parallel).
    parallel : bool
        True when the streaks are (nearly) parallel and the centre is at infinity.
    direction : ndarray, shape (2,)
        Dominant streak direction (unit (x, y), sign fixed so its largest component is positive).
    residual_px : ndarray, shape (N,)
        Distance of the centre from each streak's bisector (the RSO indicator of Sease 2013 eqs.
        4.11-4.13); NaN when parallel.
    """

    xy: NDArray[np.float64]
    parallel: bool
    direction: NDArray[np.float64]
    residual_px: NDArray[np.float64]


def _directions(first: NDArray, second: NDArray) -> NDArray[np.float64]:
    span = second - first
    return span / np.linalg.norm(span, axis=1, keepdims=True)


def dominant_direction(directions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Principal axis of unit directions (N, 2), sign-free (d and -d count the same)."""
    _, vectors = np.linalg.eigh(directions.T @ directions)
    axis = vectors[:, 1]
    return axis if axis[np.argmax(np.abs(axis))] > 0 else -axis


def centre_of_rotation(first_xy: ArrayLike, second_xy: ArrayLike, *, max_distance_px: float = 1e5,
                       outlier_z: float = OUTLIER_Z) -> CentreOfRotation:
    """Centre of rotation of N >= 2 streaks from their ends (N, 2) each (module docstring).

    With four or more streaks the fit is repeated without the streaks whose bisectors miss the
    first centre by more than ``outlier_z`` robust sigmas (an RSO or a corrupted streak would
    otherwise pull the centre, or make parallel streaks look convergent); the residuals of all
    streaks are then taken from that centre.
    """
    p1, p2 = np.asarray(first_xy, dtype=float), np.asarray(second_xy, dtype=float)
    if p1.shape != p2.shape or p1.ndim != 2 or p1.shape[1] != 2 or len(p1) < 2:
        raise InvalidInputError(f"streak ends must be two (N, 2) arrays with N >= 2, got {p1.shape}, {p2.shape}")
    d = _directions(p1, p2)
    mid = 0.5 * (p1 + p2)
    rhs = np.sum(d * mid, axis=1)
    cor = _fit(d, mid, rhs, np.ones(len(d), dtype=bool), max_distance_px)
    if len(d) >= 4:
        inliers = np.abs(_robust_z(_distances(cor, d, mid, rhs))) <= outlier_z
        if 3 <= inliers.sum() < len(d):
            cor = _fit(d, mid, rhs, inliers, max_distance_px)
    return cor


def _fit(d: NDArray, mid: NDArray, rhs: NDArray, use: NDArray[np.bool_], max_distance_px: float) -> CentreOfRotation:
    """Least-squares centre of the streaks ``use`` (or parallel); residuals of all streaks."""
    singular = np.linalg.svd(d[use], compute_uv=False)
    axis = dominant_direction(d[use])
    parallel = CentreOfRotation(np.full(2, np.nan), True, axis, np.full(len(d), np.nan))
    if singular[-1] < PARALLEL_CONDITION * singular[0]:
        return parallel
    xy, *_ = np.linalg.lstsq(d[use], rhs[use], rcond=None)
    if np.linalg.norm(xy - mid[use].mean(axis=0)) > max_distance_px:
        return parallel
    return CentreOfRotation(xy, False, axis, d @ xy - rhs)


def _distances(cor: CentreOfRotation, d: NDArray, mid: NDArray, rhs: NDArray) -> NDArray[np.float64]:
    """Bisector residuals (px) of a finite centre, or slope offsets (rad) of parallel streaks."""
    if not cor.parallel:
        return cor.residual_px
    return np.arcsin(np.clip(d @ np.array([-cor.direction[1], cor.direction[0]]), -1.0, 1.0))


def _robust_z(values: NDArray[np.float64]) -> NDArray[np.float64]:
    centre = np.median(values)
    spread = 1.4826 * float(np.median(np.abs(values - centre)))
    return (values - centre) / max(spread, 1e-12 * (1.0 + abs(centre)))


def group_endpoints(
    first_xy: ArrayLike, second_xy: ArrayLike, cor: CentreOfRotation, *, as_parallel: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Ends (N, 2) of group A and of group B, and which streaks had their ends swapped.

    ``as_parallel`` forces the parallel rule (by the dominant direction) even when a finite
    centre was found.
    """
    p1, p2 = np.asarray(first_xy, dtype=float), np.asarray(second_xy, dtype=float)
    mid = 0.5 * (p1 + p2)
    if cor.parallel or as_parallel:
        sign = (p1 - mid) @ cor.direction
    else:
        vc, v1 = mid - cor.xy, p1 - mid
        sign = vc[:, 0] * v1[:, 1] - vc[:, 1] * v1[:, 0]
    swap = sign < 0
    group_a = np.where(swap[:, None], p2, p1)
    group_b = np.where(swap[:, None], p1, p2)
    return group_a, group_b, swap
