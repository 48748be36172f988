"""Davenport's q-method for Wahba's problem.

Huffman 2006 §6.1.3 and Fowler 2013 §7 eqs. 7.4-7.10: the optimal quaternion maximises
the gain ``q^T K q`` on the unit sphere, so it is the eigenvector of Davenport's matrix K for its
largest eigenvalue. K is symmetric, and ``numpy.linalg.eigh`` solves a whole batch at once. It
is the most robust of the solvers (no characteristic polynomial, no singularity at 180 degrees)
and the reference the faster ones are compared with.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .wahba import attitude_profile_matrix, davenport_matrix, wahba_solver


def q_method_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of R with ``R r ~ b``.

    Inputs are batched unit vectors (M, N, 3) and weights (M, N) summing to one (see
    :mod:`.wahba`).
    """
    k = davenport_matrix(attitude_profile_matrix(observed, reference, weights))
    _, vectors = np.linalg.eigh(k)  # eigenvalues ascending: the last column is the optimum
    return vectors[..., :, 3]


q_method = wahba_solver(
    q_method_quaternions, name="q_method", module=__name__,
    summary="Solve Wahba's problem by Davenport's q-method.",
)
