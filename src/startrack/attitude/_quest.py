"""Shuster's QUEST (QUaternion ESTimator) for Wahba's problem.

Huffman 2006 §6.1.3 eqs. 6.30-6.35 and Fowler 2013 §7 (Fowler 2013 Ch.7, Shuster's
coefficients). With ``sigma = tr B``, ``S = B + B^T``, ``kappa = tr adj S``, ``Delta = det S``
and z (active sign, see :mod:`._wahba`), the largest eigenvalue of Davenport's K is the largest
root of

    f(lam) = lam^4 - (a + b) lam^2 - c lam + (a b + c sigma - d)
    a = sigma^2 - kappa,  b = sigma^2 + z.z,  c = Delta + z.S z,  d = z.S^2 z

found by Newton-Raphson from ``lam = sum(w)`` (= 1 with normalised weights). On ``lam >=
lam_max`` f is increasing and convex, so the iteration falls monotonically onto lam_max. The
quaternion is then ``q ~ (x, gamma)`` with

    alpha = lam^2 - sigma^2 + kappa,  beta = lam - sigma,  gamma = (lam + sigma) alpha - Delta
    x = (alpha I + beta S + S^2) z

which is the Gibbs-vector solution ``g = x / gamma`` written without the division. (x, gamma)
is the last column of adj(lam I - K), equal to ``C q q_w`` with C > 0 independent of frame, so it
vanishes for rotations by 180 degrees (q_w = 0).

180-degree singularity: Shuster's method of sequential rotations. Turning the reference frame by
180 degrees about axis k (``r -> R_k r``, i.e. ``B -> B R_k``) turns the scalar part of the
solution into +-q_k. We evaluate gamma in the original frame and the three turned frames
(cheap: only sigma, kappa and Delta change), solve in the frame with the largest |gamma| (so
|q_w| >= 1/2 there) and turn back, ``R = R' R_k``. This is the batched form of trying the frames
one after the other.

Refinement: the polynomial fixes lam_max only to about eps / f'(lam_max), and the error of q
is that over the gap g between the two largest eigenvalues of K, so plain QUEST loses accuracy
as g -> 0 (stars close together: g ~ separation^2; two stars 0.6 degrees apart already give
errors ~4e-8 rad, noise-free, and 3.4 arcmin apart ~4e-4 rad). We therefore solve the residual
problem again (references turned by the current estimate R1, ``B -> B R1^T``, whose solution
is near the identity) and compose, :data:`REFINE_PASSES` times. Each pass multiplies the error
by about eps / g (the column of adj(lam I - K) picked out is then nearly the answer: a step
of inverse iteration), so QUEST ends as accurate as the eigen-solver q-method (measured against
``Rotation.align_vectors``: ~1e-9 rad for a noisy pair 3.4 arcmin apart, ~1e-11 for a field of
0.6 degrees). Using the Rayleigh quotient ``tr(B R1^T)`` as lam instead of Newton was tried:
it is cubic when the first pass is good but converges to the wrong eigenvector when it is not.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._linalg import matvec
from ._refine import FLIP_DIAGONALS, flipped_profiles, refine, unflip
from ._wahba import WahbaResult, attitude_profile_matrix, davenport_parts, solve_with

NEWTON_MAX_ITER = 60
NEWTON_TOL = 1e-15
"""Stop Newton-Raphson when every step is below this (lam is ~1 with normalised weights)."""

REFINE_PASSES = 2
"""QUEST passes on the residual problem after the first (see the module docstring)."""

_FRAME_FLIPS = FLIP_DIAGONALS
"""Diagonals of R_k: no turn, then 180 degrees about x, y and z (:mod:`._refine`)."""


def _polynomial(sigma, s, z, kappa, delta):
    """Coefficients (a + b, c, constant term) of Shuster's characteristic polynomial, each (M,)."""
    sz = matvec(s, z)
    a = sigma**2 - kappa
    b = sigma**2 + np.sum(z * z, axis=-1)
    c = delta + np.sum(z * sz, axis=-1)
    d = np.sum(sz * sz, axis=-1)
    return a + b, c, a * b + c * sigma - d


def largest_eigenvalue(
    sigma: NDArray[np.float64],
    s: NDArray[np.float64],
    z: NDArray[np.float64],
    kappa: NDArray[np.float64],
    delta: NDArray[np.float64],
) -> NDArray[np.float64]:
    """lam_max (M,) of K by Newton-Raphson from 1 (weights normalised to sum to one).

    Takes ``sigma = tr B`` (M,), ``S`` (M, 3, 3), z (M, 3), ``kappa = tr adj S`` and
    ``Delta = det S`` (M,). Starting above the largest root, the iteration decreases
    monotonically onto it (Huffman 2006 §6.1.3; Shuster's Newton-Raphson).
    """
    ab, c, const = _polynomial(sigma, s, z, kappa, delta)
    lam = np.ones_like(sigma)
    for _ in range(NEWTON_MAX_ITER):
        f = ((lam * lam - ab) * lam - c) * lam + const
        slope = (4.0 * lam * lam - 2.0 * ab) * lam - c
        step = np.maximum(f / slope, 0.0)  # the fall is monotone; a rise is rounding
        lam = lam - step
        if not np.any(step > NEWTON_TOL):
            break
    return lam


def frame_invariants(profile):
    """sigma (M, 4), S (M, 4, 3, 3), z (M, 4, 3), kappa and Delta (M, 4) in the four frames.

    Frame 0 is the original one, frames 1-3 have the references turned by 180 degrees about x,
    y and z (``B -> B R_k``). Shared with ESOQ2, which picks its frame from the same numbers.
    """
    sigma, s, z = davenport_parts(flipped_profiles(profile))  # B R_k
    s00, s11, s22 = s[..., 0, 0], s[..., 1, 1], s[..., 2, 2]
    s01, s02, s12 = s[..., 0, 1], s[..., 0, 2], s[..., 1, 2]
    kappa = s00 * s11 - s01**2 + s00 * s22 - s02**2 + s11 * s22 - s12**2  # tr adj S
    delta = (
        s00 * (s11 * s22 - s12**2) - s01 * (s01 * s22 - s12 * s02) + s02 * (s01 * s12 - s11 * s02)
    )
    return sigma, s, z, kappa, delta


def quest_step(profile: NDArray[np.float64]) -> NDArray[np.float64]:
    """One QUEST solve: scalar-last quaternions (M, 4) from profile matrices B (M, 3, 3).

    B must be built with weights summing to one. Handles 180-degree rotations by the sequential
    rotation method (module docstring).
    """
    sigma, s, z, kappa, delta = frame_invariants(profile)
    lam = largest_eigenvalue(sigma[:, 0], s[:, 0], z[:, 0], kappa[:, 0], delta[:, 0])[:, None]
    alpha = lam**2 - sigma**2 + kappa
    gamma = (lam + sigma) * alpha - delta
    best = np.argmax(np.abs(gamma), axis=1)
    rows = np.arange(profile.shape[0])
    s_b, z_b, alpha_b = s[rows, best], z[rows, best], alpha[rows, best]
    beta_b = lam[:, 0] - sigma[rows, best]
    sz = matvec(s_b, z_b)
    x = alpha_b[:, None] * z_b + beta_b[:, None] * sz + matvec(s_b, sz)
    turned = np.concatenate([x, gamma[rows, best][:, None]], axis=1)
    turned /= np.linalg.norm(turned, axis=1, keepdims=True)
    return unflip(turned, best)  # R = R' R_k


def quest_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of R with ``R r ~ b``.

    Inputs are batched unit vectors (M, N, 3) and weights (M, N) summing to one (see
    :mod:`._wahba`). One QUEST solve plus :data:`REFINE_PASSES` passes on the residual problem.
    """
    profile = attitude_profile_matrix(observed, reference, weights)
    return refine(quest_step, profile, quest_step(profile), REFINE_PASSES)


def quest(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
          sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Solve Wahba's problem by Shuster's QUEST (accurate through 180-degree rotations by
    sequential rotations, and for close star pairs by one refinement pass).

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with the QUEST covariance when ``sigma_rad`` is given.
    """
    return solve_with(quest_quaternions, observed, reference, weights, sigma_rad=sigma_rad)
