"""QUEST measurement-model covariance of an attitude estimate.

Seed 000 §6.1.3 eq. 6.36 (notes §1.26). Each observed unit vector w_i is modelled as the true
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
    info = np.eye(3) - np.einsum("mn,mni,mnj->mij", a, observed, observed)
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
        ``P = sigma_tot^2 [I - sum_i a_i w_i w_i^T]^-1`` (seed 000 eq. 6.36 times 4, see the
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
