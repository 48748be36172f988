"""Checking and shaping the inputs shared by the Wahba solvers and the covariance.

Every public attitude function accepts one problem (vectors of shape (N, 3)) or a batch of M
problems (shape (M, N, 3)). These helpers turn both into the batched form, normalise the vectors
and raise :class:`startrack.errors.InvalidInputError` on misuse. They also decide whether a
problem is degenerate (fewer than two non-parallel directions), which is an expected failure
reported by a status, not an error.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError, as_float_array
from ._linalg import cross

MIN_SEPARATION_RAD: float = 1e-6
"""Directions closer than this (or closer than this to antiparallel) count as parallel.

Below about a micro-radian the rotation about the common axis is not resolved in float64 by the
polynomial solvers (QUEST's eigenvalue gap is about separation^2 / 2), and it is physically
meaningless for a star tracker long before that.
"""


def as_vector_batch(name: str, value: ArrayLike) -> tuple[NDArray[np.float64], bool]:
    """Unit vectors of shape (M, N, 3) from an (N, 3) or (M, N, 3) array, and whether batched.

    Raises InvalidInputError for another shape, non-finite entries or zero-length vectors.
    """
    arr = as_float_array(value, name)
    if arr.ndim not in (2, 3) or arr.shape[-1] != 3:
        raise InvalidInputError(
            f"{name} must have shape (N, 3) or (M, N, 3) (unit vectors, components last), "
            f"got shape {arr.shape}"
        )
    batched = arr.ndim == 3
    if batched and arr.shape[0] == 0:
        raise InvalidInputError(
            f"{name} must hold at least one problem (M >= 1), got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"{name} must be finite, got NaN or infinite components")
    norm = np.linalg.norm(arr, axis=-1, keepdims=True)
    if np.any(norm == 0.0):
        raise InvalidInputError(f"{name} must not contain zero-length vectors")
    arr = arr / norm
    return (arr if batched else arr[None]), batched


def as_vector_pair(
    observed: ArrayLike, reference: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], bool]:
    """Batched unit vectors (M, N, 3) of a Wahba problem; both arrays must share one shape."""
    obs, batched = as_vector_batch("observed", observed)
    ref, _ = as_vector_batch("reference", reference)
    if obs.shape != ref.shape or np.ndim(observed) != np.ndim(reference):
        raise InvalidInputError(
            "observed and reference must have the same shape, (N, 3) or (M, N, 3), got "
            f"{np.shape(observed)} and {np.shape(reference)}"
        )
    return obs, ref, batched


def as_per_vector(
    name: str, value: ArrayLike, shape: tuple[int, int], *, allow_zero: bool
) -> NDArray[np.float64]:
    """A per-vector quantity broadcast to ``shape`` = (M, N).

    Accepts a scalar, an (N,) array (the same for every problem) or an (M, N) array. Entries must
    be finite and positive (``allow_zero`` also admits zeros).
    """
    arr = as_float_array(value, name)
    m, n = shape
    if arr.shape not in ((), (n,), (m, n)):
        raise InvalidInputError(
            f"{name} must be a scalar or have shape ({n},) or ({m}, {n}) to match the vectors, "
            f"got shape {arr.shape}"
        )
    bad = ~np.isfinite(arr) | (arr < 0.0 if allow_zero else arr <= 0.0)
    if np.any(bad):
        what = "non-negative" if allow_zero else "positive"
        raise InvalidInputError(f"{name} must be finite and {what}, got {arr[bad].ravel()[:3]}")
    return np.broadcast_to(arr, shape).astype(float)


def normalised_weights(weights: NDArray[np.float64]) -> NDArray[np.float64]:
    """Weights (M, N) scaled to sum to one per problem; problems with zero total stay zero."""
    total = weights.sum(axis=-1, keepdims=True)
    return np.divide(weights, total, out=np.zeros_like(weights), where=total > 0.0)


def _spread_rad(vectors: NDArray[np.float64], used: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Largest sine of the angle between a used vector and the first used vector, shape (M,)."""
    first = np.argmax(used, axis=-1)
    anchor = np.take_along_axis(vectors, first[:, None, None], axis=1)
    sine = np.linalg.norm(cross(vectors, anchor), axis=-1)
    return np.max(np.where(used, sine, 0.0), axis=-1, initial=0.0)


def degenerate_mask(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """True for problems (M,) with fewer than two non-parallel weighted directions.

    A problem is degenerate when every vector with a non-zero weight is parallel or antiparallel
    (within :data:`MIN_SEPARATION_RAD`) to the first one, in the observed or the reference set:
    the rotation about that axis is then undetermined.
    """
    if observed.shape[1] == 0:
        return np.ones(observed.shape[0], dtype=bool)
    used = weights > 0.0
    limit = np.sin(MIN_SEPARATION_RAD)
    return (_spread_rad(observed, used) < limit) | (_spread_rad(reference, used) < limit)
