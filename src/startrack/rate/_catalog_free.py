"""Catalog-free rate from one streaked image: OLAE between the two endpoint sets.

Sease 2013 ch. 4 "Catalog-Free Rate Estimation", eqs. 4.1-4.10 (Sease 2013 Ch.4 Eq. 4.1–4.10). The
group-A end of each streak (camera vector r_i) and its group-B end (b_i) are the same star at
the two ends of the exposure, so the relative attitude ``Delta = rot_cam_B_from_cam_A`` solves
Wahba's problem between the two sets with no catalog and no identification. OLAE
(:mod:`startrack.attitude._olae`) solves it linearly and gives a residual ``e_i`` per streak
(eq. 4.7); streaks whose residual is an outlier (an RSO, an overlapping pair, a bad end) are
dropped and the rate solved again. The rate is ``omega = -rotvec(Delta) / T`` (camera frame,
rad/s, eqs. 4.9-4.10 with the frame change of Sease 2013).

Outlier rule: Sease 2013 flags ``|e_i - mean| > k sigma`` with k = 2.5 and warns that a lower
bound on sigma is needed when all streaks agree closely. Here the centre and spread are the
median and the MAD-based sigma (one outlier does not inflate them), and sigma is at least
``floor_rad``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..attitude import olae_gibbs, olae_residuals
from ..errors import InvalidInputError, as_float_array, checked_count, checked_number
from ..results import Status
from ._estimate import RateEstimate, checked_exposure, failed

METHOD = "catalog-free OLAE"
K_SIGMA = 2.5


def robust_z(values: NDArray[np.float64], floor: float) -> NDArray[np.float64]:
    """``(x - median) / max(1.4826 MAD, floor)`` of a set of indicator values (NaN-aware)."""
    centre = np.nanmedian(values)
    spread = max(1.4826 * float(np.nanmedian(np.abs(values - centre))), floor)
    return (values - centre) / spread


@dataclass(frozen=True)
class CatalogFreeRate:
    """The catalog-free rate of one image, and the residual of every streak.

    ``residuals`` (N,) are OLAE's ``e_i`` for the final solution (unitless, ~ twice the angle
    mismatch in radians); ``estimate.used`` marks the streaks kept.
    """

    estimate: RateEstimate
    residuals: NDArray[np.float64]
    gibbs: NDArray[np.float64]


def catalog_free_rate(
    vectors_a: ArrayLike,
    vectors_b: ArrayLike,
    exposure_s: float,
    *,
    k_sigma: float = K_SIGMA,
    floor_rad: float = 1e-5,
    max_rounds: int = 5,
    min_streaks: int = 3,
    initial_used: ArrayLike | None = None,
) -> CatalogFreeRate:
    """Rate between the group-A and group-B ends (N, 3) of N streaks, rejecting outliers.

    Parameters
    ----------
    vectors_a, vectors_b : array_like, shape (N, 3)
        Camera-frame unit vectors of each streak's two ends (row i is one streak).
    exposure_s : float
        Time between the two ends (the exposure), seconds.
    k_sigma : float
        Outlier threshold in robust sigmas (seed: 2.5).
    floor_rad : float
        Lower bound on the residual spread (the seed's variance floor); about twice the
        endpoint precision in radians (2 x 0.1 px x the pixel angle).
    max_rounds, min_streaks : int
        Rejection rounds; fewest streaks to keep.
    initial_used : array_like of bool, shape (N,), optional
        The streaks to start from (e.g. a :func:`consensus`); all when None. The median and
        spread of the residuals are taken over the streaks in use.

    Returns
    -------
    CatalogFreeRate
        The rate is for the A -> B order; TOO_FEW_STARS status with fewer than 2 streaks.
    """
    a, b = as_float_array(vectors_a, "vectors_a"), as_float_array(vectors_b, "vectors_b")
    if a.shape != b.shape or a.ndim != 2 or a.shape[1:] != (3,):
        raise InvalidInputError(f"vectors_a and vectors_b must both have shape (N, 3), got {a.shape}, {b.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise InvalidInputError("vectors_a and vectors_b must be finite")
    checked_exposure(exposure_s)
    checked_number(k_sigma, "k_sigma", low=0.0, above_low=True)
    checked_number(floor_rad, "floor_rad", low=0.0)
    checked_count(max_rounds, "max_rounds", 1, 1000)
    checked_count(min_streaks, "min_streaks", 2)
    a = a / np.linalg.norm(a, axis=1, keepdims=True)
    b = b / np.linalg.norm(b, axis=1, keepdims=True)
    if len(a) < 2:
        return CatalogFreeRate(failed(Status.TOO_FEW_STARS, "fewer than two streaks", METHOD),
                               np.full(len(a), np.nan), np.full(3, np.nan))
    used = np.ones(len(a), dtype=bool) if initial_used is None else np.asarray(initial_used, dtype=bool).copy()
    if used.shape != (len(a),):
        raise InvalidInputError(f"initial_used must be {len(a)} booleans, one per streak, got shape {used.shape}")
    if used.sum() < 2:
        return CatalogFreeRate(failed(Status.TOO_FEW_STARS, "fewer than two streaks", METHOD),
                               np.full(len(a), np.nan), np.full(3, np.nan))
    for _ in range(max_rounds):
        gibbs = olae_gibbs(b[used], a[used], np.full(used.sum(), 1.0 / used.sum()))
        residuals = olae_residuals(b, a, gibbs)
        centre = np.median(residuals[used])
        spread = max(1.4826 * float(np.median(np.abs(residuals[used] - centre))), floor_rad)
        keep = np.abs(residuals - centre) <= k_sigma * spread
        if keep.sum() < min(min_streaks, len(a)) or np.array_equal(keep, used):
            break
        used = keep
    return CatalogFreeRate(_estimate(gibbs, exposure_s, used), residuals, gibbs)


def _estimate(gibbs: NDArray[np.float64], exposure_s: float, used: NDArray[np.bool_]) -> RateEstimate:
    """Rate from the Gibbs vector of ``Delta``: angle 2 atan|g| about g, omega = -angle axis / T."""
    norm = np.linalg.norm(gibbs)
    rotvec = gibbs * (2.0 * np.arctan(norm) / norm) if norm > 0 else np.zeros(3)
    return RateEstimate(Status.OK, omega_rad_s=-rotvec / exposure_s, method=METHOD, used=used)


@dataclass(frozen=True)
class Consensus:
    """The largest set of streaks that agree on one rotation (:func:`consensus`).

    ``used`` (N,) marks the agreeing streaks, ``swap`` (N,) those whose ends must be exchanged
    to agree, ``gibbs`` (3,) is the rotation refitted on them.
    """

    used: NDArray[np.bool_]
    swap: NDArray[np.bool_]
    gibbs: NDArray[np.float64]


def _scores(a: NDArray, b: NDArray, gibbs: NDArray, tolerance: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Per hypothesis (H, 3) and streak: inlier (either way round), swapped, best residual (H, N)."""
    direct = olae_residuals(b[None], a[None], gibbs)
    swapped = olae_residuals(a[None], b[None], gibbs)
    best = np.minimum(direct, swapped)
    return best <= tolerance, swapped < direct, best


def consensus(
    vectors_a: ArrayLike,
    vectors_b: ArrayLike,
    tolerance: ArrayLike,
    *,
    candidates: int = 15,
    rounds: int = 3,
) -> Consensus:
    """The rotation most streaks agree with, from pairs of the first ``candidates`` streaks.

    Not in Sease 2013 (whose k-sigma rejection starts from all streaks and fails when the bad ones
    are many: the fragments of faint streaks, stars leaving the field). Each pair of the
    ``candidates`` first streaks (put the most precise first), with the second one's ends
    either way round, proposes a rotation (OLAE on two streaks); every streak whose ends fit it,
    either way round, within its ``tolerance`` (N,) (OLAE residual units, ~ radians) votes
    for it. The winner is refitted on its voters ``rounds`` times.
    """
    a, b = np.asarray(vectors_a, dtype=float), np.asarray(vectors_b, dtype=float)
    tol = np.broadcast_to(np.asarray(tolerance, dtype=float), (len(a),))
    first, second = np.triu_indices(min(candidates, len(a)), k=1)
    pair_a = np.concatenate([np.stack([a[first], a[second]], 1), np.stack([a[first], b[second]], 1)])
    pair_b = np.concatenate([np.stack([b[first], b[second]], 1), np.stack([b[first], a[second]], 1)])
    gibbs = olae_gibbs(pair_b, pair_a, np.full(pair_a.shape[:2], 0.5))
    inlier, _, best = _scores(a, b, gibbs, tol)
    votes = inlier.sum(axis=1) - 1e-6 * np.where(inlier, best / tol, 0.0).sum(axis=1)
    g = gibbs[np.argmax(votes)]
    for _ in range(rounds):
        inlier, swap, _ = _scores(a, b, g[None], tol)
        used, swap = inlier[0], swap[0]
        if used.sum() < 2:
            break
        aa, bb = np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)
        g = olae_gibbs(bb[used], aa[used], np.full(used.sum(), 1.0 / used.sum()))
    inlier, swap, _ = _scores(a, b, g[None], tol)
    return Consensus(inlier[0], swap[0], g)


def regroup(vectors_a: ArrayLike, vectors_b: ArrayLike, *, rounds: int = 2) -> NDArray[np.bool_]:
    """Which streaks (N,) to swap so that every streak's ends agree with the common rotation.

    The centre-of-rotation sign rule (:mod:`._grouping`) can put the ends of a few streaks in the
    wrong groups when the centre is poorly determined (streaks nearly parallel, or the curved
    trails of a wide field). Given a grouping that is right for most streaks, a robust OLAE fit
    gives the common rotation, and a streak whose swapped ends fit it better is swapped.
    """
    a, b = np.asarray(vectors_a, dtype=float), np.asarray(vectors_b, dtype=float)
    swap = np.zeros(len(a), dtype=bool)
    for _ in range(rounds):
        aa, bb = np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)
        fit = catalog_free_rate(aa, bb, 1.0, floor_rad=1e-9)
        if not fit.estimate.ok:
            break
        worse = olae_residuals(aa, bb, fit.gibbs) < fit.residuals  # swapped ends fit better
        if not np.any(worse):
            break
        swap ^= worse
    return swap
