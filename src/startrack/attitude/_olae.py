"""OLAE, the Optimal Linear Attitude Estimator (Mortari, Markley and Singla 2007).

Sease 2013 ch. 4 eqs. 4.1-4.7 (Sease 2013 Ch.4 Eq. 4.1–4.10). With the sums and differences of each
pair, ``s_i = b_i + r_i`` and ``d_i = b_i - r_i``, the Cayley form of a rotation with Gibbs
(Rodrigues) vector g is exactly ``d_i = g x s_i``, linear in g. OLAE solves it in the
least-squares sense,

    min_g  sum_i w_i |d_i + [s_i x] g|^2    =>    (sum_i w_i (|s_i|^2 I - s_i s_i^T)) g = sum_i w_i s_i x d_i

and returns ``q ~ (g, 1)``. The residuals ``e_i = |d_i + [s_i x] g|`` (eq. 4.7) flag the pairs
that do not move with the rest (the RSO indicator of :mod:`startrack.rate._rso`).

Sease 2013 writes the system with factors of 1/2 that cancel; its eq. 4.8 (the attitude matrix)
has sign typos, so the quaternion goes to scipy directly (Sease 2013).

As a Wahba solver: OLAE's loss is not Wahba's, so one solve is near-optimal only for small
rotations; and g is infinite at 180 degrees. Here the first solve is done in whichever of the
original frame and the three frames turned by 180 degrees about x, y, z (:mod:`._refine`) gives
the smallest rotation, and the problem is then solved again on the residual (references turned
by the estimate), whose fixed point ``sum_i w_i b_i x R r_i = 0`` is the Wahba optimum. Written
as ``q ~ (adj(M) v, det M)`` (no division), the first solve stays finite at 180 degrees.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..frames import cross
from ._linalg import quat_product
from ._refine import FLIP_DIAGONALS, unflip
from ._wahba import WahbaResult, solve_with

MAX_PASSES = 8
"""Most OLAE solves of the residual problem after the first."""
PASS_TOL_RAD = 1e-12
"""Stop the passes when every correction is smaller than this angle (the next would be ~1e-16)."""


def olae_system(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """OLAE's normal matrix M (..., 3, 3) and right-hand side v (..., 3) (module docstring)."""
    s = observed + reference
    d = observed - reference
    s2 = np.sum(s * s, axis=-1)
    matrix = np.einsum("...n,...n,ij->...ij", weights, s2, np.eye(3))
    matrix = matrix - np.einsum("...n,...ni,...nj->...ij", weights, s, s)
    rhs = np.einsum("...n,...ni->...i", weights, cross(s, d))
    return matrix, rhs


def olae_gibbs(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """One OLAE solve: the Gibbs vectors g (..., 3) (no frame turn; singular at 180 degrees).

    A problem whose normal matrix is exactly singular (its directions coincide, e.g. a camera of a
    1e-300 deg field) gets NaN, and the others their solution; numpy raised LinAlgError for the batch.
    """
    matrix, rhs = olae_system(observed, reference, weights)
    try:
        solved = np.linalg.solve(matrix, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:  # LU met a zero pivot, so det (the same LU) is exactly 0 there
        singular = np.linalg.det(matrix) == 0.0
        solved = np.linalg.solve(np.where(singular[..., None, None], np.eye(3), matrix), rhs[..., None])[..., 0]
        solved[singular] = np.nan
    return np.asarray(solved, dtype=np.float64)


def olae_residuals(
    observed: NDArray[np.float64], reference: NDArray[np.float64], gibbs: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Per-pair residual norms ``|d_i + s_i x g|`` (..., N) of Sease 2013 eq. 4.7 (unitless)."""
    s = observed + reference
    d = observed - reference
    return np.linalg.norm(d + cross(s, gibbs[..., None, :]), axis=-1)


def _adjugate_solution(matrix: NDArray[np.float64], rhs: NDArray[np.float64]) -> NDArray[np.float64]:
    """Quaternions ``(adj(M) v, det M)`` (..., 4), normalised, of symmetric systems M g = v.

    All zero where both vanish (the rotation is exactly 180 degrees in that frame); such a frame
    has scalar part 0 and is never the one chosen.
    """
    c0, c1, c2 = matrix[..., 0], matrix[..., 1], matrix[..., 2]
    adj = np.stack([cross(c1, c2), cross(c2, c0), cross(c0, c1)], axis=-2)  # rows of adj(M)
    vector = (adj @ rhs[..., None])[..., 0]
    det = np.sum(c0 * cross(c1, c2), axis=-1)
    quat = np.concatenate([vector, det[..., None]], axis=-1)
    norm = np.linalg.norm(quat, axis=-1, keepdims=True)
    return quat / np.where(norm > 0.0, norm, 1.0)  # a frame at exactly 180 degrees gives 0 / 0


def _first_solve(observed, reference, weights) -> NDArray[np.float64]:
    """OLAE in the frame (original or turned by 180 degrees) giving the smallest rotation, (M, 4)."""
    turned = reference[:, None, :, :] * FLIP_DIAGONALS[None, :, None, :]  # T_k r, (M, 4, N, 3)
    matrix, rhs = olae_system(observed[:, None], turned, weights[:, None])
    quat = _adjugate_solution(matrix, rhs)
    frame = np.argmax(np.abs(quat[..., 3]), axis=1)
    rows = np.arange(observed.shape[0])
    return unflip(quat[rows, frame], frame)


def olae_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of R with ``R r ~ b`` (module docstring)."""
    quat = _first_solve(observed, reference, weights)
    for _ in range(MAX_PASSES):
        turned = np.einsum("mij,mnj->mni", Rotation.from_quat(quat).as_matrix(), reference)
        gibbs = olae_gibbs(observed, turned, weights)
        step = np.concatenate([gibbs, np.ones_like(gibbs[:, :1])], axis=1)
        step /= np.linalg.norm(step, axis=1, keepdims=True)
        quat = quat_product(step, quat)
        if not np.any(2.0 * np.linalg.norm(gibbs, axis=1) > PASS_TOL_RAD):
            break
    return quat


def olae(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
         sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Solve Wahba's problem by OLAE with residual passes (module docstring).

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with the QUEST covariance when ``sigma_rad`` is given.
    """
    return solve_with(olae_quaternions, observed, reference, weights, sigma_rad=sigma_rad)
