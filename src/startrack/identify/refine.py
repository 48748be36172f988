"""Least-squares refinement of an attitude (and optionally the focal length) from matched stars.

Minimises the pixel residuals between detected stars and their catalog stars projected through
the camera, over a small rotation of the camera frame and, when it is free, the logarithm of the
focal length (fx and fy scale together). Gauss-Newton with the analytic Jacobian of
:meth:`startrack.camera.Camera.project_with_jacobian`; a few iterations suffice.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera

_MAX_ITER = 6
_CONVERGED = 1e-9
"""Stop when no parameter moves more than this (radians, or relative focal length)."""


def _skew(v: NDArray) -> NDArray:
    """Cross-product matrices [v x], shape (N, 3, 3)."""
    zero = np.zeros(v.shape[0])
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    return np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1), np.stack([-y, x, zero], -1)], 1)


def _rodrigues(rotvec: NDArray) -> NDArray:
    """Rotation matrix of a rotation vector (radians)."""
    angle = float(np.sqrt(rotvec @ rotvec))
    if angle < 1e-15:
        return np.eye(3)
    k = _skew(rotvec[None] / angle)[0]
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def _step(matrix: NDArray, camera: Camera, ref_icrs: NDArray, x: NDArray, y: NDArray, fit_focal: bool,
          fit_k1: bool = False) -> NDArray:
    """One Gauss-Newton step for the parameters (rotation vector, [ln f], [k1])."""
    cam_vec = ref_icrs @ matrix.T
    px, py, jac_v = camera.project_with_jacobian(cam_vec)
    # A small rotation d of the camera frame moves c to c + d x c = c - [c x] d.
    jac = -np.einsum("nij,njk->nik", jac_v, _skew(cam_vec))  # (N, 2, 3)
    if fit_focal:
        jac_f = np.stack([px - camera.cx, py - camera.cy], axis=1)[:, :, None]  # d / d ln f
        jac = np.concatenate([jac, jac_f], axis=2)
    if fit_k1:  # d / d k1 of x = cx + fx a (1 + k1 r^2 + ...), with a, b the pinhole coordinates
        a, b = cam_vec[:, 0] / cam_vec[:, 2], cam_vec[:, 1] / cam_vec[:, 2]
        r2 = a * a + b * b
        jac = np.concatenate([jac, np.stack([camera.fx * a * r2, camera.fy * b * r2], axis=1)[:, :, None]], axis=2)
    jac = jac.reshape(-1, jac.shape[2])
    res = np.stack([px - x, py - y], axis=1).reshape(-1)
    normal = jac.T @ jac
    try:
        return np.linalg.solve(normal, -(jac.T @ res))
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(jac, -res, rcond=None)[0]


def refine_pointing(rot_cam_from_icrs: Rotation, camera: Camera, ref_icrs: NDArray, x: NDArray,
                    y: NDArray, *, fit_focal: bool,
                    fit_k1: bool = False) -> tuple[Rotation, Camera, NDArray[np.float64]]:
    """Refine the attitude (and focal length) to matched stars.

    Parameters
    ----------
    rot_cam_from_icrs : Rotation
        Starting attitude.
    camera : Camera
        Starting camera; only its focal length changes when ``fit_focal``.
    ref_icrs : ndarray, shape (K, 3)
        ICRS unit vectors of the matched catalog stars.
    x, y : ndarray, shape (K,)
        Detected positions (pixels) of the same stars.
    fit_focal : bool
        Also fit the focal length (needs at least 3 stars; otherwise it stays fixed).
    fit_k1 : bool
        Also fit the first radial distortion coefficient (with the focal length; needs at least
        8 stars). For photographs from lenses nobody calibrated.

    Returns
    -------
    rotation, camera, residual_px
        The refined attitude and camera and each star's pixel residual distance, shape (K,).
    """
    fit_focal = fit_focal and len(x) >= 3
    fit_k1 = fit_k1 and fit_focal and len(x) >= 8
    matrix = rot_cam_from_icrs.as_matrix()
    for _ in range(_MAX_ITER):
        delta = _step(matrix, camera, ref_icrs, x, y, fit_focal, fit_k1)
        matrix = _rodrigues(delta[:3]) @ matrix
        if fit_focal:
            camera = camera.with_focal(camera.fx * np.exp(delta[3]))
        if fit_k1:
            camera = camera.with_distortion(k1=camera.k1 + delta[4])
        if np.max(np.abs(delta)) < _CONVERGED:
            break
    px, py = camera.vector_to_pixel(ref_icrs @ matrix.T)
    return Rotation.from_matrix(matrix), camera, np.hypot(px - x, py - y)
