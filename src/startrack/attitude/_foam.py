"""Markley's FOAM (Fast Optimal Attitude Matrix) for Wahba's problem.

Huffman 2006 §6.1.5 eqs. 6.54-6.58 (Markley 1993). Without a decomposition of B:

    R = [(kappa + |B|^2) B + lam adj(B^T) - B B^T B] / zeta
    kappa = (lam^2 - |B|^2) / 2,   zeta = kappa lam - det B

where |.| is the Frobenius norm and lam the largest root of Markley's quartic

    (lam^2 - |B|^2)^2 - 8 lam det B - 4 |adj B|^2 = 0

(= s1 + s2 + d s3 of the SVD method), found by Newton-Raphson from lam = 1 (weights summing to
one; the iteration falls monotonically onto the root). FOAM has no 180-degree singularity; like
QUEST it loses digits when the two largest eigenvalues of Davenport's K are close (a narrow
field, two close stars), so the residual problem is solved again (:mod:`._refine`).

Covariance (Huffman 2006 §6.1.5, standard form): ``P = sigma_tot^2 (kappa I + B B^T) / zeta`` (camera
frame, rad^2) with B built from the normalised weights ``sigma_tot^2 / sigma_i^2``; it equals the
SVD covariance exactly.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..frames import cross
from ._refine import refine
from ._wahba import WahbaResult, attitude_profile_matrix, sigma_weighted_profile, solve_with

NEWTON_MAX_ITER = 60
NEWTON_TOL = 1e-15
REFINE_PASSES = 2
"""FOAM passes on the residual problem after the first (as for QUEST)."""


def _cofactor(profile: NDArray[np.float64]) -> NDArray[np.float64]:
    """adj(B^T) = adj(B)^T (M, 3, 3): columns c1 x c2, c2 x c0, c0 x c1 of B's columns c_k."""
    c0, c1, c2 = profile[..., :, 0], profile[..., :, 1], profile[..., :, 2]
    return np.stack([cross(c1, c2), cross(c2, c0), cross(c0, c1)], axis=-1)


def foam_parts(profile: NDArray[np.float64]):
    """lam (M,), kappa (M,), zeta (M,), |B|^2 (M,) and adj(B^T) (M, 3, 3) of profiles (M, 3, 3)."""
    norm2 = np.sum(profile**2, axis=(-2, -1))
    det = np.linalg.det(profile)
    cof = _cofactor(profile)
    adj2 = np.sum(cof**2, axis=(-2, -1))
    lam = np.ones_like(norm2)
    for _ in range(NEWTON_MAX_ITER):
        diff = lam * lam - norm2
        f = diff * diff - 8.0 * lam * det - 4.0 * adj2
        slope = 4.0 * lam * diff - 8.0 * det
        step = np.maximum(np.divide(f, slope, out=np.zeros_like(f), where=slope > 0.0), 0.0)
        lam = lam - step
        if not np.any(step > NEWTON_TOL):
            break
    kappa = 0.5 * (lam * lam - norm2)
    zeta = kappa * lam - det
    return lam, kappa, zeta, norm2, cof


def foam_step(profile: NDArray[np.float64]) -> NDArray[np.float64]:
    """One FOAM solve: scalar-last quaternions (M, 4) from profiles B (M, 3, 3), weights summing to 1."""
    lam, kappa, zeta, norm2, cof = foam_parts(profile)
    bbtb = profile @ np.swapaxes(profile, -1, -2) @ profile
    matrix = (kappa + norm2)[:, None, None] * profile + lam[:, None, None] * cof - bbtb
    return Rotation.from_matrix(matrix / zeta[:, None, None]).as_quat()


def foam_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of R with ``R r ~ b``."""
    profile = attitude_profile_matrix(observed, reference, weights)
    return refine(foam_step, profile, foam_step(profile), REFINE_PASSES)


def foam_covariance(
    observed: NDArray[np.float64],
    reference: NDArray[np.float64],
    weights: NDArray[np.float64],
    sigma_rad: NDArray[np.float64],
) -> NDArray[np.float64]:
    """FOAM covariance (M, 3, 3), camera frame, rad^2 (module docstring)."""
    sigma_tot2, profile = sigma_weighted_profile(observed, reference, sigma_rad)
    _, kappa, zeta, _, _ = foam_parts(profile)
    bbt = profile @ np.swapaxes(profile, -1, -2)
    return (sigma_tot2 / zeta)[:, None, None] * (kappa[:, None, None] * np.eye(3) + bbt)


def foam(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
         sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Solve Wahba's problem by Markley's FOAM.

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with the FOAM covariance when ``sigma_rad`` is given.
    """
    return solve_with(foam_quaternions, observed, reference, weights, sigma_rad=sigma_rad, covariance=foam_covariance)
