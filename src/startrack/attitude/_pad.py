"""Predictive attitude determination (Crassidis and Markley), Huffman 2006 §6.1.2.

Huffman 2006 eqs. 6.9-6.17. A predicted attitude A (camera from reference) is
corrected by the small rotation phi that best explains the measured vectors:

    b_i ~ exp([phi x]) A r_i ~ p_i - [p_i x] phi,    p_i = A r_i
    phi = -F^-1 sum_i [p_i x]^T W_i (b_i - p_i),      F = sum_i [p_i x]^T W_i [p_i x]

(the seed's eq. 6.13, written for our active rotations; W_i = R_i^-1 is the information of
measurement i in the plane perpendicular to it, ``I / sigma_i^2`` when isotropic). The seed
divides phi by the time step: its "model error" d is the angular rate that carries A(t_k) to
the attitude seen at t_{k+1} (:func:`predictive_update`, ``omega = -phi / dt`` in our
convention ``dA/dt = -[omega x] A``), and F^-1 is the covariance of the corrected attitude,
equal to QUEST's for isotropic errors. Its advantage over QUEST is the anisotropic R_i of
measurement i (a streak's endpoint is better known across the streak than along it).

As a Wahba solver (method "pad"), the correction is iterated from the TRIAD attitude, a
Gauss-Newton solution of Wahba's loss, until it is below :data:`PASS_TOL_RAD`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ..frames import cross
from ._inputs import as_per_vector, as_vector_pair
from ._triad import triad_quaternions
from ._wahba import WahbaResult, solve_with

MAX_PASSES = 10
PASS_TOL_RAD = 1e-12
"""Stop iterating when every correction is below this angle (the next would be ~1e-16)."""


def _information(predicted: NDArray[np.float64], info: NDArray[np.float64]) -> NDArray[np.float64]:
    """F = sum_i [p_i x]^T W_i [p_i x] (M, 3, 3) for predicted vectors p (M, N, 3), W (M, N, 3, 3)."""
    skew = _skew(predicted)
    return np.einsum("mnki,mnkl,mnlj->mij", skew, info, skew)


def _skew(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cross-product matrices [v x] (..., 3, 3)."""
    out = np.zeros(v.shape + (3,))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def pad_correction(
    matrices: NDArray[np.float64],
    observed: NDArray[np.float64],
    reference: NDArray[np.float64],
    info: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Correction rotation vectors phi (M, 3) and information F (M, 3, 3) for attitudes (M, 3, 3).

    ``info`` (M, N, 3, 3) is each measurement's information matrix W_i (rad^-2).
    """
    predicted = np.einsum("mij,mnj->mni", matrices, reference)
    big_f = _information(predicted, info)
    # [p x]^T W (b - p) = -[p x] W (b - p); with W isotropic in the tangent plane it is W p x b.
    rhs = np.einsum("mnki,mnkl,mnl->mi", _skew(predicted), info, observed - predicted)
    return -np.linalg.solve(big_f, rhs[..., None])[..., 0], big_f


def _isotropic(weights: NDArray[np.float64]) -> NDArray[np.float64]:
    return weights[..., None, None] * np.eye(3)


def isotropic_correction(
    matrices: NDArray[np.float64],
    observed: NDArray[np.float64],
    reference: NDArray[np.float64],
    weights: NDArray[np.float64],
) -> NDArray[np.float64]:
    """:func:`pad_correction` for ``W_i = w_i I``: ``phi = F^-1 sum w p x b``, F = sum w (I - p p^T)."""
    predicted = np.einsum("mij,mnj->mni", matrices, reference)
    big_f = np.sum(weights, axis=1)[:, None, None] * np.eye(3)
    big_f = big_f - np.einsum("mn,mni,mnj->mij", weights, predicted, predicted)
    rhs = np.einsum("mn,mni->mi", weights, cross(predicted, observed))
    return np.linalg.solve(big_f, rhs[..., None])[..., 0]


def pad_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: Gauss-Newton from TRIAD, quaternions (M, 4) of R with ``R r ~ b``."""
    rotation = Rotation.from_quat(triad_quaternions(observed, reference, weights))
    for _ in range(MAX_PASSES):
        phi = isotropic_correction(rotation.as_matrix(), observed, reference, weights)
        rotation = Rotation.from_rotvec(phi) * rotation
        if not np.any(np.linalg.norm(phi, axis=1) > PASS_TOL_RAD):
            break
    return rotation.as_quat()


def pad(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
        sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Solve Wahba's problem by iterated predictive attitude determination (module docstring).

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with the QUEST covariance when ``sigma_rad`` is given.
    """
    return solve_with(pad_quaternions, observed, reference, weights, sigma_rad=sigma_rad)


@dataclass(frozen=True)
class PredictiveUpdate:
    """One step of predictive attitude determination (Huffman 2006 §6.1.2).

    Attributes
    ----------
    rotation : Rotation
        Corrected attitude at the measurement time (maps reference vectors to the camera frame).
    omega_rad_s : ndarray, shape (3,)
        The seed's model error d: the constant angular velocity (camera frame, rad/s) that
        carries the prior attitude to the corrected one over ``dt_s``.
    covariance_rad2 : ndarray, shape (3, 3)
        F^-1, covariance of the corrected attitude's small-angle error, camera frame.
    """

    rotation: Rotation
    omega_rad_s: NDArray[np.float64]
    covariance_rad2: NDArray[np.float64]


def _measurement_information(obs, sigma_rad, measurement_cov_rad2) -> NDArray[np.float64]:
    """Information matrices W_i (1, N, 3, 3) from isotropic sigmas or full covariances (rad^2)."""
    if measurement_cov_rad2 is None:
        sigma = as_per_vector("sigma_rad", sigma_rad, obs.shape[:2], allow_zero=False)
        return _isotropic(1.0 / sigma**2)
    cov = np.asarray(measurement_cov_rad2, dtype=float)
    if cov.shape != obs.shape[1:] + (3,) or not np.all(np.isfinite(cov)):
        raise InvalidInputError(
            f"measurement_cov_rad2 must be finite with shape ({obs.shape[1]}, 3, 3), got {cov.shape}"
        )
    radial = obs[0, :, :, None] * obs[0, :, None, :]  # unobservable direction: unit variance
    return np.linalg.inv(cov + radial)[None]


def predictive_update(
    rotation: Rotation,
    observed: ArrayLike,
    reference: ArrayLike,
    dt_s: float,
    *,
    sigma_rad: ArrayLike = 1.0,
    measurement_cov_rad2: ArrayLike | None = None,
) -> PredictiveUpdate:
    """Correct an attitude with the vectors measured ``dt_s`` later, and the rate between.

    Parameters
    ----------
    rotation : Rotation
        Attitude (camera from reference) at the previous time t_k.
    observed, reference : array_like, shape (N, 3)
        Camera vectors measured at t_k + dt and their reference (e.g. ICRS) directions; N >= 2.
    dt_s : float
        Time between the attitude and the measurements, seconds (> 0).
    sigma_rad : float or array_like (N,)
        Isotropic 1-sigma error of each measured vector, radians.
    measurement_cov_rad2 : array_like, shape (N, 3, 3), optional
        Full covariance R_i of each measured vector (rad^2, in the plane perpendicular to it);
        replaces ``sigma_rad``.

    Returns
    -------
    PredictiveUpdate
        Corrected attitude, the model-error rate and the covariance. One Gauss-Newton step
        (seed eq. 6.13): accurate while the rotation over dt is small (well under a degree).
    """
    obs, ref, batched = as_vector_pair(observed, reference)
    if batched:
        raise InvalidInputError(f"observed must have shape (N, 3) for one update, got {np.shape(observed)}")
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise InvalidInputError(f"dt_s must be a positive number of seconds, got {dt_s!r}")
    info = _measurement_information(obs, sigma_rad, measurement_cov_rad2)
    phi, big_f = pad_correction(rotation.as_matrix()[None], obs, ref, info)
    corrected = Rotation.from_rotvec(phi[0]) * rotation
    return PredictiveUpdate(corrected, -phi[0] / dt_s, np.linalg.inv(big_f[0]))
