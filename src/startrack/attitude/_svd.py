"""Markley's SVD method for Wahba's problem.

Huffman 2006 §6.1.4 eqs. 6.37-6.53 (Markley 1988). With the profile matrix
``B = sum_i w_i b_i r_i^T = U diag(s1, s2, s3) V^T`` (s1 >= s2 >= s3 >= 0) and
``d = det U det V``, the optimum is

    R = U diag(1, 1, d) V^T,         loss_min = 1 - s1 - s2 - d s3   (weights summing to one)

exact for any rotation angle and for rank-2 B (two vectors). ``numpy.linalg.svd`` decomposes a
whole batch at once.

Covariance (Huffman 2006 §6.1.4, the body-frame form): with ``U+ = U diag(1, 1, det U)``,

    P = sigma_tot^2 U+ diag(1 / (s2 + d s3), 1 / (d s3 + s1), 1 / (s1 + s2)) U+^T

in the camera (observed) frame, rad^2, where the s_i come from B built with the normalised
weights ``a_i = sigma_tot^2 / sigma_i^2``. It equals the QUEST covariance for noise-free data and
differs from it at second order in the noise.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ._wahba import WahbaResult, attitude_profile_matrix, sigma_weighted_profile, solve_with


def _signed_svd(profile: NDArray[np.float64]):
    """U+ (M, 3, 3), the singular values with d s3 (M, 3) and V+ (M, 3, 3) of profiles (M, 3, 3)."""
    u, s, vt = np.linalg.svd(profile)
    det_u, det_v = np.linalg.det(u), np.linalg.det(vt)
    u[:, :, 2] *= det_u[:, None]
    vt[:, 2, :] *= det_v[:, None]
    s = s.copy()
    s[:, 2] *= det_u * det_v
    return u, s, vt


def svd_quaternions(
    observed: NDArray[np.float64], reference: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Solver core: scalar-last quaternions (M, 4) of ``R = U+ V+^T`` (module docstring)."""
    u, _, vt = _signed_svd(attitude_profile_matrix(observed, reference, weights))
    return Rotation.from_matrix(u @ vt).as_quat()


def svd_covariance(
    observed: NDArray[np.float64],
    reference: NDArray[np.float64],
    weights: NDArray[np.float64],
    sigma_rad: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Markley's SVD covariance (M, 3, 3), camera frame, rad^2 (module docstring)."""
    sigma_tot2, profile = sigma_weighted_profile(observed, reference, sigma_rad)
    u, s, _ = _signed_svd(profile)
    diag = 1.0 / np.stack([s[:, 1] + s[:, 2], s[:, 2] + s[:, 0], s[:, 0] + s[:, 1]], axis=-1)
    return sigma_tot2[:, None, None] * (u * diag[:, None, :]) @ np.swapaxes(u, -1, -2)


def svd_method(observed: ArrayLike, reference: ArrayLike, weights: ArrayLike | None = None, *,
               sigma_rad: ArrayLike | None = None) -> WahbaResult:
    """Solve Wahba's problem by Markley's SVD method.

    Parameters and result as :func:`~startrack.attitude.solve_wahba` (without ``method``):
    ``result.rotation.apply(reference) ~ observed``, with the SVD covariance when ``sigma_rad`` is given.
    """
    return solve_with(svd_quaternions, observed, reference, weights, sigma_rad=sigma_rad, covariance=svd_covariance)
