"""Davenport's q-method for Wahba's problem.

Huffman 2006 §6.1.3 and Fowler 2013 §7 eqs. 7.4-7.10: the optimal quaternion maximises
the gain ``q^T K q`` on the unit sphere, so it is the eigenvector of Davenport's matrix K for its
largest eigenvalue. K is symmetric, and ``numpy.linalg.eigh`` solves a whole batch at once. It
is the most robust of the solvers (no characteristic polynomial, no singularity at 180 degrees)
and the reference the faster ones are compared with.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._wahba import WahbaResult, attitude_profile_matrix, davenport_matrix, solve_with


def q_method_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of R with ``R r ~ b``.

    Inputs are batched unit vectors (M, N, 3) and weights (M, N) summing to one (see
    :mod:`._wahba`).
    """
    k = davenport_matrix(attitude_profile_matrix(observed, reference, weights))
    _, vectors = np.linalg.eigh(k)  # eigenvalues ascending: the last column is the optimum
    return vectors[..., :, 3]


def q_method(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
             sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Solve Wahba's problem by Davenport's q-method.

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with the QUEST covariance when ``sigma_rad`` is given.
    """
    return solve_with(q_method_quaternions, observed, reference, weights, sigma_rad=sigma_rad)
