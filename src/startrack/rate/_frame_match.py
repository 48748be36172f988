"""The same stars in two unidentified frames, and the rate they give only when they agree.

Huffman 2006 §7.2 and Samaan 2002 step 6 match the stars of consecutive frames by proximity. Nearest
neighbours alone fail when the stars move by a sizeable fraction of their spacing: one wrong pair
among a handful bends the fitted rotation, the second round then keeps only the pairs that fit the
bent rotation, and the rate comes out tens of percent (or tens of deg/s) wrong with nothing to say
so. Here (not in the seeds) the association is a consensus, as :func:`.catalog_free.consensus` does
for streaks: every two candidate pairs (stars of frame a and b within the motion gate of each other)
whose angular separation is the same in both frames propose a rotation; the rotation that carries
the most stars of frame a onto a star of frame b within a tolerance of a few centroid sigmas wins,
and is refitted on its pairs. :func:`rate_from_frames` then reports a rate only with enough pairs
to both fix and check the rotation, and when their misfit is what the centroid noise explains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations
from numbers import Integral

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..attitude import solve_wahba
from ..catalog import chord_from_angle, query_cone
from ..errors import InvalidInputError, is_real_number, require
from ..frames import angle_between, checked_angle, checked_unit_vectors, normalize
from ..results import Status
from ..units import DEG
from ._estimate import RateEstimate, failed
from ._from_vectors import METHOD, rate_from_vectors

MIN_PAIRS = 4
"""Fewest matched stars for a rate from two frames: two fix the rotation, the others check it."""
TOL_SIGMAS = 4.0
"""Default matching tolerance, in sigmas of the difference of a star's two positions."""
MAX_BIRGE = 3.0
"""Largest rms misfit of the matched stars to one rotation, in sigmas of the centroid noise."""
NEAR_FACTOR = 3.0
MIN_FIT_FRACTION = 0.75
"""Of the stars within ``NEAR_FACTOR`` matching tolerances of the fitted rotation, the fraction that
must be within one: the tolerance would otherwise hide a scatter larger than the stated noise, by
keeping the few pairs that happen to fit (with that noise, all but ~3e-4 of them fit)."""
SEED_STARS = 12
"""Stars of frame a (the first ones: pass the brightest first) whose pairs propose rotations."""
REFINE_ROUNDS = 3


def _mutual_nearest(a: NDArray, b: NDArray, max_angle_rad: float) -> NDArray[np.intp]:
    """Index pairs (K, 2) of mutual nearest neighbours closer than the angle (chord metric)."""
    chord = chord_from_angle(min(max_angle_rad, math.pi), "max_angle_rad")
    dist_ab, nearest_b = cKDTree(b).query(a, distance_upper_bound=chord)
    _, nearest_a = cKDTree(a).query(b)
    ia = np.flatnonzero(np.isfinite(dist_ab))
    ib = nearest_b[ia]
    keep = nearest_a[ib] == ia
    return np.stack([ia[keep], ib[keep]], axis=1)


def _triad(a1: NDArray, a2: NDArray, b1: NDArray, b2: NDArray) -> NDArray[np.float64]:
    """Rotation matrices (H, 3, 3) taking a1 onto b1 and the plane (a1, a2) onto (b1, b2) (TRIAD)."""

    def frame(u: NDArray, v: NDArray) -> NDArray:
        t2 = normalize(np.cross(u, v))
        return np.stack([u, t2, np.cross(u, t2)], axis=-1)

    return frame(b1, b2) @ np.swapaxes(frame(a1, a2), -1, -2)


def _hypotheses(a: NDArray, b: NDArray, candidates: list[NDArray], tol_rad: float) -> NDArray[np.float64]:
    """Rotations (H, 3, 3) proposed by two candidate pairs of the seed stars with equal separations."""
    seeds = [i for i in range(len(a)) if len(candidates[i])][:SEED_STARS]
    rotations = []
    for i, k in combinations(seeds, 2):
        base = float(angle_between(a[i], a[k]))
        if base < 4.0 * tol_rad:
            continue  # too short a baseline to fix the roll about it
        j, m = (g.ravel() for g in np.meshgrid(candidates[i], candidates[k], indexing="ij"))
        fit = (j != m) & (np.abs(angle_between(b[j], b[m]) - base) <= 2.0 * tol_rad)
        if np.any(fit):
            n = int(fit.sum())
            rotations.append(_triad(np.tile(a[i], (n, 1)), np.tile(a[k], (n, 1)), b[j[fit]], b[m[fit]]))
    return np.concatenate(rotations) if rotations else np.zeros((0, 3, 3))


def _best(a: NDArray, b: NDArray, rotations: NDArray, tol_rad: float) -> NDArray[np.float64]:
    """The rotation (3, 3) that brings the most stars of a within ``tol_rad`` of a star of b."""
    chord = chord_from_angle(tol_rad, "tol_rad")
    dist, _ = cKDTree(b).query(np.einsum("hij,nj->hni", rotations, a).reshape(-1, 3), distance_upper_bound=chord)
    dist = dist.reshape(len(rotations), len(a))
    inlier = np.isfinite(dist)
    score = inlier.sum(axis=1) - 1e-3 * np.where(inlier, dist / chord, 0.0).sum(axis=1)
    return rotations[int(np.argmax(score))]


def _refined(a: NDArray, b: NDArray, rotation: Rotation, tol_rad: float) -> NDArray[np.intp]:
    """Mutual nearest pairs within ``tol_rad`` of the rotation, refitted on them a few times."""
    pairs = _mutual_nearest(rotation.apply(a), b, tol_rad)
    for _ in range(REFINE_ROUNDS):
        if len(pairs) < 2:
            break
        fit = solve_wahba(b[pairs[:, 1]], a[pairs[:, 0]])
        if not fit.ok:
            break
        pairs = _mutual_nearest(require(fit.rotation, "the pairs' rotation").apply(a), b, tol_rad)
    return pairs


def match_frames(
    vectors_a: ArrayLike,
    vectors_b: ArrayLike,
    max_angle_rad: float,
    *,
    predicted: Rotation | None = None,
    tol_rad: float | None = None,
) -> NDArray[np.intp]:
    """Pairs (K, 2) of indices ``(i_a, i_b)`` of the same stars in two unidentified lists.

    Parameters
    ----------
    vectors_a, vectors_b : array_like, shape (Na, 3), (Nb, 3)
        Camera-frame unit vectors of the stars found in each frame, brightest first (the first
        :data:`SEED_STARS` of frame a propose the rotations).
    max_angle_rad : float
        The motion gate: the largest motion of a star between the frames left after the
        prediction (radians, in (0, pi]).
    predicted : Rotation, optional
        Predicted ``rot_cam_b_from_cam_a`` (e.g. ``exp(-[omega x] dt)`` from a previous rate);
        the identity by default.
    tol_rad : float, optional
        How closely a matched star must fit the common rotation (radians, at most
        ``max_angle_rad``): about 4 sigmas of the difference of its two positions. Default a
        tenth of ``max_angle_rad``, at least 1e-4 rad.

    Returns
    -------
    ndarray of int, shape (K, 2)
        The pairs that agree with one rotation (module docstring), each star in at most one
        pair. When no two candidate pairs agree: the one mutual-nearest pair within the gate if
        there is exactly one (it cannot be checked), else none.
    """
    a, b = checked_unit_vectors(vectors_a, "vectors_a"), checked_unit_vectors(vectors_b, "vectors_b")
    gate = checked_angle(max_angle_rad, "max_angle_rad")
    tol = max(0.1 * gate, 1e-4) if tol_rad is None else checked_angle(tol_rad, "tol_rad", gate)
    if predicted is not None and (not isinstance(predicted, Rotation) or not predicted.single):
        raise InvalidInputError(f"predicted must be a single scipy Rotation or None, got {predicted!r}")
    if len(a) == 0 or len(b) == 0:
        return np.zeros((0, 2), dtype=np.intp)
    turn = Rotation.identity() if predicted is None else predicted
    turned = turn.apply(a)
    candidates = [np.asarray(c, dtype=np.intp) for c in query_cone(cKDTree(b), turned, gate)]
    hypotheses = _hypotheses(turned, b, candidates, tol)
    if len(hypotheses) == 0:
        nearest = _mutual_nearest(turned, b, gate)
        return nearest if len(nearest) == 1 else np.zeros((0, 2), dtype=np.intp)
    best = Rotation.from_matrix(_best(turned, b, hypotheses, tol)) * turn
    return _refined(a, b, best, tol)


@dataclass(frozen=True)
class FrameRate:
    """The rate between two frames with the star pairs it rests on.

    Attributes
    ----------
    estimate : RateEstimate
        The rate (camera frame, rad/s) with its covariance, or a status and reason: NO_MATCH
        (no star matched), TOO_FEW_STARS (fewer than ``min_pairs``), DEGENERATE (the pairs do not
        fit one rotation within the centroid noise, or fix no rotation).
    pairs : ndarray of int, shape (K, 2)
        Indices ``(i_a, i_b)`` of the matched stars used (all matched ones when not OK).
    residuals_rad : ndarray, shape (K,)
        Angle between each star of frame b and its frame-a star turned by the fitted rotation
        (NaN when there is no fit).
    """

    estimate: RateEstimate
    pairs: NDArray[np.intp]
    residuals_rad: NDArray[np.float64]

    @property
    def residual_rms_rad(self) -> float:
        """Root mean square of ``residuals_rad`` (NaN without pairs or a fit)."""
        return float(np.sqrt(np.mean(self.residuals_rad**2))) if len(self.residuals_rad) else float("nan")


def _fit(a: NDArray, b: NDArray, pairs: NDArray, dt_s: float, sigma_rad: float) -> tuple[RateEstimate, NDArray]:
    """Rate from the pairs, and each pair's misfit (rad) to the rotation."""
    est = rate_from_vectors(a[pairs[:, 0]], b[pairs[:, 1]], dt_s, sigma_rad=math.sqrt(2.0) * sigma_rad)
    if not est.ok:
        return est, np.full(len(pairs), np.nan)
    delta = Rotation.from_rotvec(-est.omega_rad_s * dt_s)
    return est, angle_between(delta.apply(a[pairs[:, 0]]), b[pairs[:, 1]])


def _checked_inputs(dt_s: float, sigma_rad: float, min_pairs: int) -> None:
    if not (is_real_number(dt_s) and math.isfinite(dt_s) and dt_s != 0):
        raise InvalidInputError(f"dt_s must be a finite, non-zero number of seconds, got {dt_s!r}")
    checked_angle(sigma_rad, "sigma_rad", 0.1)
    if isinstance(min_pairs, bool) or not isinstance(min_pairs, Integral) or min_pairs < 2:
        raise InvalidInputError(f"min_pairs must be an integer >= 2, got {min_pairs!r}")


def rate_from_frames(
    vectors_a: ArrayLike,
    vectors_b: ArrayLike,
    dt_s: float,
    *,
    max_angle_rad: float,
    sigma_rad: float,
    predicted: Rotation | None = None,
    min_pairs: int = MIN_PAIRS,
    max_birge: float = MAX_BIRGE,
) -> FrameRate:
    """Camera-frame rate from the stars of two unidentified frames ``dt_s`` apart, when trustworthy.

    Parameters
    ----------
    vectors_a, vectors_b : array_like, shape (Na, 3), (Nb, 3)
        Camera-frame unit vectors of the stars found in each frame, brightest first.
    dt_s : float
        Time from frame a to frame b, seconds (finite, non-zero).
    max_angle_rad : float
        The motion gate of :func:`match_frames` (radians).
    sigma_rad : float
        1-sigma centroid error of one star in one frame, per axis (radians, in (0, 0.1]): sets
        the matching tolerance (:data:`TOL_SIGMAS` sigmas of a pair's difference), the misfit
        check and the covariance.
    predicted : Rotation, optional
        Predicted ``rot_cam_b_from_cam_a``, as for :func:`match_frames`.
    min_pairs : int
        Fewest matched stars for a rate (>= 2; default :data:`MIN_PAIRS`).
    max_birge : float
        Largest rms misfit of the pairs to the rotation, in sigmas of a pair's difference.

    Returns
    -------
    FrameRate
        Status OK only with at least ``min_pairs`` pairs that fit one rotation within the noise
        (:data:`MIN_FIT_FRACTION` of the stars near it, and an rms misfit of at most ``max_birge``
        sigmas); the covariance is scaled up by the misfit (Birge ratio) when it exceeds the noise.
    """
    _checked_inputs(dt_s, sigma_rad, min_pairs)
    a, b = checked_unit_vectors(vectors_a, "vectors_a"), checked_unit_vectors(vectors_b, "vectors_b")
    gate = checked_angle(max_angle_rad, "max_angle_rad")
    tol = min(TOL_SIGMAS * math.sqrt(2.0) * sigma_rad, gate)
    if min(len(a), len(b)) < min_pairs:
        reason = (f"{len(a)} and {len(b)} stars found in the two frames; {min_pairs} in each are needed to fix "
                  "and check the rotation")
        return FrameRate(failed(Status.TOO_FEW_STARS, reason, METHOD), np.zeros((0, 2), dtype=np.intp), np.zeros(0))
    pairs = match_frames(a, b, gate, predicted=predicted, tol_rad=tol)
    if len(pairs) < min_pairs:
        return _too_few_matched(pairs, len(a), len(b), min_pairs, gate)
    est, residuals = _fit(a, b, pairs, dt_s, sigma_rad)
    if est.ok:
        near = len(_mutual_nearest(Rotation.from_rotvec(-est.omega_rad_s * dt_s).apply(a), b,
                                   min(NEAR_FACTOR * tol, gate)))
        if len(pairs) < MIN_FIT_FRACTION * near:
            reason = (f"only {len(pairs)} of the {near} stars near the fitted rotation fit it within the centroid "
                      "noise: the centroids scatter more than sigma_rad, or the matches are wrong")
            return FrameRate(failed(Status.DEGENERATE, reason, METHOD), pairs, residuals)
    return _judged(est, pairs, residuals, sigma_rad, max_birge)


def _too_few_matched(pairs: NDArray, n_a: int, n_b: int, min_pairs: int, gate_rad: float) -> FrameRate:
    """NO_MATCH (no pair) or TOO_FEW_STARS (fewer than ``min_pairs``), saying to widen the gate."""
    hint = f"if the stars move farther than {gate_rad / DEG:.3g} deg between the frames, raise max_angle_rad"
    if len(pairs) == 0:
        reason = f"no stars matched between the frames ({n_a} and {n_b} stars found): {hint}"
        return FrameRate(failed(Status.NO_MATCH, reason, METHOD), pairs, np.zeros(0))
    reason = (f"only {len(pairs)} of the stars matched between the frames ({n_a} and {n_b} found; "
              f"{min_pairs} needed to fix and check the rotation): {hint}")
    return FrameRate(failed(Status.TOO_FEW_STARS, reason, METHOD), pairs, np.full(len(pairs), np.nan))


def _judged(est: RateEstimate, pairs: NDArray, residuals: NDArray, sigma_rad: float, max_birge: float) -> FrameRate:
    """The fit, or DEGENERATE when its pairs misfit the rotation beyond the centroid noise."""
    if not est.ok:
        return FrameRate(est, pairs, residuals)
    dof = max(2 * len(pairs) - 3, 1)
    birge = math.sqrt(float(np.sum(residuals**2)) / dof) / (math.sqrt(2.0) * sigma_rad)
    if birge > max_birge:
        reason = (f"the {len(pairs)} matched stars misfit one rotation by {birge:.1f} sigma of the centroid "
                  f"noise (> {max_birge:g}): wrong matches, or a larger centroid error than given")
        return FrameRate(failed(Status.DEGENERATE, reason, METHOD), pairs, residuals)
    cov = require(est.covariance_rad2_s2, "the rate covariance") * max(birge, 1.0) ** 2
    return FrameRate(RateEstimate(Status.OK, "", est.omega_rad_s, cov, METHOD), pairs, residuals)
