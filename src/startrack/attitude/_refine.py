"""Turning a Wahba problem into a nearby one, and refining a solution on the residual problem.

Two tricks shared by the closed-form solvers (QUEST, FOAM, ESOQ2, OLAE):

- *Turned reference frames* (Shuster's method of sequential rotations): turning every reference
  vector by a known rotation T (``r -> T r``) turns the profile matrix into ``B T^T`` and the
  solution into ``R T^-1``; a solver with a singular or imprecise rotation angle (QUEST and OLAE
  at 180 degrees, ESOQ2 at 0 degrees) solves in a frame where it is well conditioned and turns
  back.
- *Refinement passes*: once an estimate R1 is known, the residual problem (references turned by
  R1, ``B -> B R1^T``) has a solution near a known rotation, where a polynomial solver's
  rounding error is smallest; solving it again and composing is one step of inverse iteration.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ._linalg import quat_product

ProfileStep = Callable[[NDArray[np.float64]], NDArray[np.float64]]
"""A single solve: profile matrices B (M, 3, 3) -> scalar-last quaternions (M, 4)."""

FLIP_DIAGONALS = np.array([[1.0, 1.0, 1.0], [1.0, -1.0, -1.0], [-1.0, 1.0, -1.0], [-1.0, -1.0, 1.0]])
"""Diagonals of the turns T_k: none, then 180 degrees about x, y and z."""

FLIP_QUATS = np.array(
    [[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]
)
"""Scalar-last quaternions of T_k, in the order of :data:`FLIP_DIAGONALS`."""


def flipped_profiles(profile: NDArray[np.float64]) -> NDArray[np.float64]:
    """``B T_k`` for the four turns T_k (T_k is its own inverse and transpose), shape (M, 4, 3, 3)."""
    return profile[:, None, :, :] * FLIP_DIAGONALS[None, :, None, :]


def unflip(quat_turned: NDArray[np.float64], index: NDArray[np.intp]) -> NDArray[np.float64]:
    """Quaternions (M, 4) of ``R = R' T_k`` from solutions R' of the problems turned by T_k."""
    return quat_product(quat_turned, FLIP_QUATS[index])


def residual_profile(profile: NDArray[np.float64], quat: NDArray[np.float64]) -> NDArray[np.float64]:
    """``B R1^T`` (M, 3, 3): the profile of the problem whose references are turned by R1."""
    matrix = Rotation.from_quat(quat).as_matrix()
    return profile @ np.swapaxes(matrix, -1, -2)


def refine(
    step: ProfileStep,
    profile: NDArray[np.float64],
    quat: NDArray[np.float64],
    passes: int,
    *,
    offset_quat: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Solve the residual problem ``passes`` times and compose (quaternions (M, 4) in and out).

    ``offset_quat`` (a single scalar-last quaternion O) turns the residual problem further, so
    that its solution is near O instead of the identity (ESOQ2 is imprecise near the identity and
    solves near 180 degrees instead): each pass solves ``B (O R1)^T`` and returns ``R' O R1``.
    """
    for _ in range(passes):
        start = quat if offset_quat is None else quat_product(offset_quat[None, :], quat)
        quat = quat_product(step(residual_profile(profile, start)), start)
    return quat
