"""Mortari's ESOQ2 (second EStimator of the Optimal Quaternion) for Wahba's problem.

Sease 2013 §3 eq. 3.23 (Sease 2013 Eq. 3.22–3.23, the solver Sease uses at both streak ends) and
Samaan 2002 step 5 (Mortari 2000). Writing the optimal quaternion as ``q = (e sin(phi/2),
cos(phi/2))`` (rotation axis e, angle phi), the eigen-equation ``(K - lam I) q = 0`` of
Davenport's K (:mod:`._wahba`, active convention) splits into

    z.e sin(phi/2) = (lam - sigma) cos(phi/2)
    M e = 0,    M = (lam - sigma)(S - (lam + sigma) I) + z z^T

so the axis is the null vector of the symmetric 3 x 3 matrix M (rank 2): the largest of the
cross products of its rows. Then ``q ~ ((lam - sigma) e, z.e)``. lam is the largest root of the
same characteristic quartic as QUEST's (:func:`.quest.largest_eigenvalue`).

ESOQ2 is exact at 180 degrees (z.e = 0) but loses relative precision near the identity, where
both lam - sigma and z vanish. The remedy is QUEST's in reverse: of the original frame and the
three frames turned by 180 degrees about x, y, z (:mod:`._refine`), solve in the one where the
solution is farthest from the identity, the smallest ``|gamma|`` of QUEST (proportional to the
scalar part in that frame), and turn back. The refinement passes solve the residual problem
turned by 180 degrees about x, for the same reason.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..frames import cross
from ._quest import frame_invariants, largest_eigenvalue
from ._refine import FLIP_QUATS, refine, unflip
from ._wahba import WahbaResult, attitude_profile_matrix, solve_with

REFINE_PASSES = 2


def _null_vectors(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit null vectors (M, 3) of rank-2 symmetric matrices (M, 3, 3): the largest row cross product."""
    rows = [matrix[:, 0], matrix[:, 1], matrix[:, 2]]
    candidates = np.stack([cross(rows[0], rows[1]), cross(rows[1], rows[2]), cross(rows[2], rows[0])], axis=1)
    norms = np.linalg.norm(candidates, axis=-1)
    best = np.argmax(norms, axis=1)
    pick = np.arange(matrix.shape[0])
    return candidates[pick, best] / norms[pick, best][:, None]


def esoq2_step(profile: NDArray[np.float64]) -> NDArray[np.float64]:
    """One ESOQ2 solve: scalar-last quaternions (M, 4) from profiles B (M, 3, 3), weights summing to 1."""
    sigma, s, z, kappa, delta = frame_invariants(profile)
    lam = largest_eigenvalue(sigma[:, 0], s[:, 0], z[:, 0], kappa[:, 0], delta[:, 0])[:, None]
    gamma = (lam + sigma) * (lam**2 - sigma**2 + kappa) - delta  # ~ scalar part in each frame
    frame = np.argmin(np.abs(gamma), axis=1)
    rows = np.arange(profile.shape[0])
    s_f, z_f, sig_f, lam_f = s[rows, frame], z[rows, frame], sigma[rows, frame], lam[:, 0]
    beta = lam_f - sig_f
    matrix = beta[:, None, None] * (s_f - (lam_f + sig_f)[:, None, None] * np.eye(3))
    matrix = matrix + z_f[:, :, None] * z_f[:, None, :]
    axis = _null_vectors(matrix)
    quat = np.concatenate([beta[:, None] * axis, np.sum(z_f * axis, axis=-1, keepdims=True)], axis=1)
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return unflip(quat, frame)


def esoq2_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of R with ``R r ~ b``."""
    profile = attitude_profile_matrix(observed, reference, weights)
    return refine(esoq2_step, profile, esoq2_step(profile), REFINE_PASSES, offset_quat=FLIP_QUATS[1])


def esoq2(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
          sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Solve Wahba's problem by Mortari's ESOQ2.

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with the QUEST covariance when ``sigma_rad`` is given.
    """
    return solve_with(esoq2_quaternions, observed, reference, weights, sigma_rad=sigma_rad)
