"""Legendre-Gauss-Lobatto (LGL) nodes, quadrature weights and differentiation matrix.

The pseudo-spectral discretisation of Sease 2013 ch. 5 eq. 5.8 (Sease 2013 Chapter 5):
N nodes on [-1, 1] made of the two ends and the N - 2 roots of P'_{N-1}, the derivative of the
Legendre polynomial of degree N - 1. Standard results (Canuto, Hussaini, Quarteroni & Zang,
*Spectral Methods*, 2006, §2.3; Fahroo & Ross 2002, J. Guid. Control Dyn. 25(1), 160):

* weights ``w_i = 2 / (N (N - 1) P_{N-1}(tau_i)^2)``: sum_i w_i f(tau_i) is exact for
  polynomials of degree <= 2N - 3;
* ``D_ij = P_{N-1}(tau_i) / (P_{N-1}(tau_j) (tau_i - tau_j))`` for i != j,
  ``D_00 = -N (N - 1) / 4``, ``D_{N-1,N-1} = N (N - 1) / 4``, other diagonal terms 0:
  ``D @ f(tau)`` is the derivative of the interpolating polynomial at the nodes, exact for
  polynomials of degree <= N - 1.

On a time interval [t0, t0 + tf] the nodes are ``t = t0 + (tau + 1) tf / 2``, derivatives scale by
``2 / tf`` and integrals by ``tf / 2`` (:func:`time_nodes`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre
from numpy.typing import NDArray

from ..errors import InvalidInputError

MIN_NODES = 4
"""Fewest nodes the virtual-motion-camouflage planner can use (two fixed ends, two solved)."""


@dataclass(frozen=True)
class LGLGrid:
    """An LGL grid on [-1, 1].

    Attributes
    ----------
    tau : ndarray, shape (N,)
        Nodes, increasing from -1 to 1.
    weights : ndarray, shape (N,)
        Quadrature weights (they sum to 2).
    diff : ndarray, shape (N, N)
        Differentiation matrix d/dtau.
    """

    tau: NDArray[np.float64]
    weights: NDArray[np.float64]
    diff: NDArray[np.float64]

    @property
    def n(self) -> int:
        return int(self.tau.size)


def lgl_grid(n_nodes: int) -> LGLGrid:
    """Nodes, weights and differentiation matrix of ``n_nodes`` LGL points (>= 2).

    Raises
    ------
    InvalidInputError
        If ``n_nodes`` is not a whole number >= 2.
    """
    if not (isinstance(n_nodes, int | np.integer) and n_nodes >= 2):
        raise InvalidInputError(f"n_nodes must be a whole number >= 2, got {n_nodes!r}")
    n = int(n_nodes)
    p_last = np.zeros(n)
    p_last[-1] = 1.0  # the Legendre series of P_{N-1}
    interior = legendre.legroots(legendre.legder(p_last)) if n > 2 else np.zeros(0)
    tau = np.concatenate([[-1.0], np.sort(np.real(interior)), [1.0]])
    p_at = legendre.legval(tau, p_last)
    weights = 2.0 / (n * (n - 1) * p_at**2)
    return LGLGrid(tau=tau, weights=weights, diff=_diff_matrix(tau, p_at))


def _diff_matrix(tau: NDArray, p_at: NDArray) -> NDArray[np.float64]:
    n = tau.size
    gap = tau[:, None] - tau[None, :]
    np.fill_diagonal(gap, 1.0)
    diff = (p_at[:, None] / p_at[None, :]) / gap
    np.fill_diagonal(diff, 0.0)
    diff[0, 0] = -n * (n - 1) / 4.0
    diff[-1, -1] = n * (n - 1) / 4.0
    return diff


def time_nodes(grid: LGLGrid, t0_s: float, tf_s: float) -> NDArray[np.float64]:
    """The grid's nodes mapped to times ``t0_s .. t0_s + tf_s`` (s)."""
    return t0_s + 0.5 * (grid.tau + 1.0) * tf_s
