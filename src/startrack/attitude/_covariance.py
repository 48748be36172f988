"""QUEST measurement-model covariance of an attitude estimate.

Huffman 2006 §6.1.3 eq. 6.36. Each observed unit vector w_i is modelled as the true
direction plus isotropic small-angle noise perpendicular to it, with per-axis standard deviation
sigma_i (radians); the optimal weights are ``a_i = sigma_tot^2 / sigma_i^2`` with
``1 / sigma_tot^2 = sum_i 1 / sigma_i^2``. The covariance of the small-angle attitude error is

    P = sigma_tot^2 [I - sum_i a_i w_i w_i^T]^-1                 (rad^2)

The seed prints ``P_QQ = P / 4``, the covariance of the quaternion vector part (a rotation by a
small angle theta has vector part theta / 2); we return the angle covariance P.

Frame: P is built from the *observed* vectors, so it is the covariance of the error rotation
vector in the camera (observed, body) frame, ``e = (truth * estimate.inv()).as_rotvec()`` for
``rot_cam_from_icrs`` attitudes (that rotation acts on camera-frame vectors). For a narrow field
of view the variance about the boresight (+z, roll) is much larger than across it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ._inputs import as_per_vector, as_vector_batch, degenerate_mask


def covariance_batch(
    observed: NDArray[np.float64], sigma_rad: NDArray[np.float64]
) -> NDArray[np.float64]:
    """QUEST covariance (M, 3, 3) from unit vectors (M, N, 3) and sigmas (M, N), no checks.

    The problems must not be degenerate (the matrix to invert is singular when they are).
    """
    inv_var = 1.0 / sigma_rad**2
    sigma_tot2 = 1.0 / inv_var.sum(axis=-1)
    a = inv_var * sigma_tot2[:, None]
    info = np.eye(3) - np.swapaxes(observed * a[..., None], -1, -2) @ observed
    return sigma_tot2[:, None, None] * np.linalg.inv(info)


def attitude_covariance(observed: ArrayLike, sigma_rad: ArrayLike) -> NDArray[np.float64]:
    """Covariance of the small-angle attitude error, camera frame, rad^2 (QUEST model).

    Parameters
    ----------
    observed : array_like, shape (N, 3) or (M, N, 3)
        Observed (camera-frame) directions of the stars used in the fit; normalised here.
    sigma_rad : float or array_like, shape (N,) or (M, N)
        1-sigma angular error of each observed direction, radians per axis perpendicular to it.

    Returns
    -------
    ndarray, shape (3, 3) or (M, 3, 3)
        ``P = sigma_tot^2 [I - sum_i a_i w_i w_i^T]^-1`` (Huffman 2006 eq. 6.36 times 4, see the
        module docstring), the covariance of ``(truth * estimate.inv()).as_rotvec()``. All NaN
        for a problem with fewer than two non-parallel vectors.

    Raises
    ------
    InvalidInputError
        Bad shapes, non-finite or zero vectors, or non-positive sigmas.
    """
    obs, batched = as_vector_batch("observed", observed)
    sigma = as_per_vector("sigma_rad", sigma_rad, obs.shape[:2], allow_zero=False)
    ok = ~degenerate_mask(obs, obs, np.ones(obs.shape[:2]))
    cov = np.full(obs.shape[:1] + (3, 3), np.nan)
    if np.any(ok):
        cov[ok] = covariance_batch(obs[ok], sigma[ok])
    return cov if batched else cov[0]


def roll_cross_boresight(
    covariance_rad2: ArrayLike, boresight: ArrayLike = (0.0, 0.0, 1.0)
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """1-sigma attitude uncertainty about the boresight (roll) and across it, radians.

    Parameters
    ----------
    covariance_rad2 : array_like, shape (..., 3, 3)
        Attitude covariance in the camera frame (rad^2), e.g. from :func:`attitude_covariance`.
    boresight : array_like, shape (3,)
        The roll axis in the same frame; the camera's +z by default.

    Returns
    -------
    sigma_roll_rad, sigma_cross_rad : ndarray, shape (...)
        ``sqrt(u^T P u)`` for the boresight u, and the rms of the two cross-boresight sigmas,
        ``sqrt((tr P - u^T P u) / 2)``. Huffman 2006 §7.2: for a narrow field the roll
        sigma is about ``f / d`` times the cross-boresight one (d the star spread in pixels).
    """
    cov = np.asarray(covariance_rad2, dtype=float)
    axis = np.asarray(boresight, dtype=float)
    if cov.shape[-2:] != (3, 3) or axis.shape != (3,) or not np.linalg.norm(axis) > 0:
        raise InvalidInputError(
            f"covariance_rad2 must have shape (..., 3, 3) and boresight be a non-zero 3-vector, "
            f"got {cov.shape} and {axis.shape}"
        )
    axis = axis / np.linalg.norm(axis)
    var_roll = np.einsum("i,...ij,j->...", axis, cov, axis)
    var_cross = 0.5 * (np.trace(cov, axis1=-2, axis2=-1) - var_roll)
    return np.sqrt(var_roll), np.sqrt(var_cross)


def roll_cross_boresight_error(
    truth: Rotation, estimate: Rotation
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Actual attitude error split into roll and cross-boresight parts, radians.

    The error rotation ``truth * estimate.inv()`` acts on camera vectors; its rotation vector's
    z component is the roll error and the length of its (x, y) part the pointing error (the
    angle between the true and estimated boresights, to first order). Fowler 2013 Ch. 7 §III.B
    ("pointing and boresight-roll components", whose formula the seed does not give).
    """
    error = (truth * estimate.inv()).as_rotvec()
    return np.abs(error[..., 2]), np.hypot(error[..., 0], error[..., 1])
