"""Averaging attitudes: Markley's eigenvector method.

Fowler 2013 §7 eqs. 7.12-7.13 (Fowler 2013 Ch.7; Markley, Cheng, Crassidis and Oshman
2007). The weighted average of unit quaternions q_k is the unit eigenvector of

    M = sum_k w_k q_k q_k^T           (4 x 4)

for its largest eigenvalue. It maximises ``sum_k w_k (q . q_k)^2``, so it does not care about the
sign of each q_k (q and -q are the same attitude), and it is the rotation minimising the weighted
sum of squared chordal (Frobenius) distances to the inputs. scipy's ``Rotation.mean`` computes
the same thing for one set; this module averages many sets at once and returns the spread.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError, as_float_array


def average_quaternions(quaternions: ArrayLike, weights: ArrayLike | None = None) -> NDArray[np.float64]:
    """Markley average of scalar-last unit quaternions.

    Parameters
    ----------
    quaternions : array_like, shape (..., K, 4)
        Sets of K quaternions (scalar last, any sign); normalised here.
    weights : array_like, shape (K,) or (..., K), optional
        Non-negative weights, not all zero in a set; equal by default.

    Returns
    -------
    ndarray, shape (..., 4)
        The average, scalar last, with a non-negative scalar part.
    """
    quat = as_float_array(quaternions, "quaternions")
    if quat.ndim < 2 or quat.shape[-1] != 4 or quat.shape[-2] == 0 or not np.all(np.isfinite(quat)):
        raise InvalidInputError(f"quaternions must be finite with shape (..., K, 4), K >= 1, got {quat.shape}")
    norm = np.linalg.norm(quat, axis=-1, keepdims=True)
    if np.any(norm == 0.0):
        raise InvalidInputError("quaternions must not be zero")
    quat = quat / norm
    w = np.ones(quat.shape[:-1]) if weights is None else as_float_array(weights, "weights")
    try:
        w = np.broadcast_to(w, quat.shape[:-1])
    except ValueError:
        shape = quat.shape[:-1]
        raise InvalidInputError(f"weights must have shape (K,) or (..., K) = {shape}, got {w.shape}") from None
    if np.any(~np.isfinite(w) | (w < 0.0)) or np.any(w.sum(axis=-1) <= 0.0):
        raise InvalidInputError("weights must be finite, non-negative and not all zero in a set")
    matrix = np.einsum("...k,...ki,...kj->...ij", w, quat, quat)
    _, vectors = np.linalg.eigh(matrix)
    mean = vectors[..., :, 3]
    return mean * np.where(mean[..., 3:] < 0.0, -1.0, 1.0)


def average_rotations(rotations: Rotation, weights: ArrayLike | None = None) -> Rotation:
    """Markley average of a stack of K rotations (a single Rotation), Fowler 2013 eq. 7.13."""
    quat = rotations.as_quat()
    if quat.ndim != 2:
        raise InvalidInputError("rotations must be a stack of rotations, not a single one")
    return Rotation.from_quat(average_quaternions(quat, weights))


def attitude_scatter(rotations: Rotation, mean: Rotation) -> NDArray[np.float64]:
    """Sample covariance (3, 3), rad^2, of the error vectors ``(r_k * mean.inv()).as_rotvec()``.

    The errors act on vectors of the rotations' output (camera) frame; divided by K - 1. Useful
    to check a sequence of attitudes against its predicted covariance.
    """
    errors = (rotations * mean.inv()).as_rotvec()
    if errors.ndim != 2 or errors.shape[0] < 2:
        raise InvalidInputError("rotations must be a stack of at least 2 rotations")
    return np.cov(errors, rowvar=False)
