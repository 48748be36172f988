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
_CONVERGED = 1e-10


def _skew(v: NDArray) -> NDArray:
    """Cross-product matrices [v x], shape (N, 3, 3)."""
    zero = np.zeros(v.shape[0])
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    return np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1), np.stack([-y, x, zero], -1)], 1)


def _step(rot: Rotation, camera: Camera, ref_icrs: NDArray, x: NDArray, y: NDArray, fit_focal: bool):
    """One Gauss-Newton step: (parameter update, pixel residuals before it)."""
    cam_vec = rot.apply(ref_icrs)
    px, py, jac_v = camera.project_with_jacobian(cam_vec)
    # A small rotation d of the camera frame moves c to c + d x c = c - [c x] d.
    jac = -np.einsum("nij,njk->nik", jac_v, _skew(cam_vec))  # (N, 2, 3)
    if fit_focal:
        jac_f = np.stack([px - camera.cx, py - camera.cy], axis=1)[:, :, None]  # d / d ln f
        jac = np.concatenate([jac, jac_f], axis=2)
    res = np.stack([px - x, py - y], axis=1)
    delta, *_ = np.linalg.lstsq(jac.reshape(-1, jac.shape[2]), -res.reshape(-1), rcond=None)
    return delta, res


def refine_pointing(rot_cam_from_icrs: Rotation, camera: Camera, ref_icrs: NDArray, x: NDArray,
                    y: NDArray, *, fit_focal: bool) -> tuple[Rotation, Camera, NDArray[np.float64]]:
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

    Returns
    -------
    rotation, camera, residual_px
        The refined attitude and camera and each star's pixel residual distance, shape (K,).
    """
    fit_focal = fit_focal and len(x) >= 3
    rot = rot_cam_from_icrs
    for _ in range(_MAX_ITER):
        delta, _ = _step(rot, camera, ref_icrs, x, y, fit_focal)
        rot = Rotation.from_rotvec(delta[:3]) * rot
        if fit_focal:
            camera = camera.with_focal(camera.fx * np.exp(delta[3]))
        if np.max(np.abs(delta)) < _CONVERGED:
            break
    px, py = camera.vector_to_pixel(rot.apply(ref_icrs))
    return rot, camera, np.hypot(px - x, py - y)
