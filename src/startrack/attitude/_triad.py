"""TRIAD: the attitude from two vector pairs.

Jacobs 1995 §4.1.6.1 (Shuster and Oh 1981) and Fowler 2013 eqs. 7.1-7.3 (Fowler 2013 Ch.7).
Two orthonormal triads are built, one from the observed pair and one from the reference pair,

    t1 = v1,   t2 = v1 x v2 / |v1 x v2|,   t3 = t1 x t2

and the rotation is ``R = [t1 t2 t3]_obs [t1 t2 t3]_ref^T``, which maps the first reference
vector exactly onto the first observed one and the plane of the pair onto the plane of the pair.

Which two vectors of a larger set: TRIAD trusts the *anchor* v1 completely, and the rotation
about it comes from v2 alone, with a variance ``sigma_2^2 / |v1 x v2|^2`` (the covariance below).
So the anchor is the vector with the largest weight (the most precise), and v2 the one that
maximises ``w_i |v1 x v_i|^2`` (the smallest variance about the anchor). The other vectors are
not used: TRIAD is not the Wahba optimum when N > 2 (nor for two vectors of unequal weights), and
its covariance is Shuster and Oh's, not QUEST's:

    P = s1^2 I + |b1 x b2|^-2 [(s2^2 - s1^2) b1 b1^T + s1^2 (b1 . b2)(b1 b2^T + b2 b1^T)]

(camera frame, rad^2; s1, s2 the per-axis angular sigmas of the anchor and the second vector;
derived for this module from the first-order error of each triad axis.)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..frames import cross
from ._wahba import WahbaResult, solve_with


def triad_pair(
    observed: NDArray[np.float64], weights: NDArray[np.float64]
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Indices (M,) of the anchor (largest weight) and of the vector maximising ``w |b1 x b|^2``."""
    rows = np.arange(observed.shape[0])
    anchor = np.argmax(weights, axis=1)
    b1 = observed[rows, anchor]
    sine2 = np.sum(cross(observed, b1[:, None, :]) ** 2, axis=-1)
    second = np.argmax(weights * sine2, axis=1)
    return anchor, second


def _triads(first: NDArray[np.float64], second: NDArray[np.float64]) -> NDArray[np.float64]:
    """Matrices (M, 3, 3) whose columns are the triad of (first, second) vectors (M, 3)."""
    normal = cross(first, second)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    return np.stack([first, normal, cross(first, normal)], axis=-1)


def triad_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of R with ``R r ~ b`` (pair of :func:`triad_pair`)."""
    rows = np.arange(observed.shape[0])
    anchor, second = triad_pair(observed, weights)
    obs = _triads(observed[rows, anchor], observed[rows, second])
    ref = _triads(reference[rows, anchor], reference[rows, second])
    return Rotation.from_matrix(obs @ np.swapaxes(ref, -1, -2)).as_quat()


def triad_covariance(
    observed: NDArray[np.float64],
    reference: NDArray[np.float64],
    weights: NDArray[np.float64],
    sigma_rad: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Shuster and Oh's TRIAD covariance (M, 3, 3), camera frame, rad^2 (module docstring)."""
    rows = np.arange(observed.shape[0])
    anchor, second = triad_pair(observed, weights)
    b1, b2 = observed[rows, anchor], observed[rows, second]
    s1, s2 = sigma_rad[rows, anchor], sigma_rad[rows, second]
    cosine = np.sum(b1 * b2, axis=-1)
    sine2 = np.sum(cross(b1, b2) ** 2, axis=-1)
    outer11 = b1[:, :, None] * b1[:, None, :]
    mixed = b1[:, :, None] * b2[:, None, :]
    mixed = mixed + np.swapaxes(mixed, -1, -2)
    bracket = (s2**2 - s1**2)[:, None, None] * outer11 + (s1**2 * cosine)[:, None, None] * mixed
    return (s1**2)[:, None, None] * np.eye(3) + bracket / sine2[:, None, None]


def triad(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
          sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Attitude by TRIAD from the best pair of the given vectors (module docstring); exact on
    noise-free data, not the optimum of more than two noisy vectors.

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with TRIAD's own covariance when ``sigma_rad`` is given.
    """
    return solve_with(triad_quaternions, observed, reference, weights, sigma_rad=sigma_rad, covariance=triad_covariance)
