"""Least-squares refinement of an attitude (and optionally the focal length) from matched stars.

Minimises the pixel residuals between detected stars and their catalog stars projected through
the camera, over a small rotation in the camera frame and, when it is free, the logarithm of the
focal length (both fx and fy scale together). Gauss-Newton with a numerical Jacobian: the
problems are tiny (tens of stars, three or four parameters).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera

_STEP = 1e-7
_MAX_ITER = 8


def _residuals(params: NDArray, rot: Rotation, camera: Camera, ref_icrs: NDArray,
               x: NDArray, y: NDArray) -> NDArray:
    r = Rotation.from_rotvec(params[:3]) * rot
    cam = camera if params.size == 3 else camera.with_focal(camera.fx * np.exp(params[3]))
    px, py = cam.vector_to_pixel(r.apply(ref_icrs))
    return np.concatenate([px - x, py - y])


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
        The refined attitude and camera and the per-star pixel residual distance, shape (K,).
    """
    n_params = 4 if fit_focal and len(x) >= 3 else 3
    params = np.zeros(n_params)
    for _ in range(_MAX_ITER):
        res = _residuals(params, rot_cam_from_icrs, camera, ref_icrs, x, y)
        jac = np.empty((res.size, n_params))
        for j in range(n_params):
            step = np.zeros(n_params)
            step[j] = _STEP
            jac[:, j] = (_residuals(params + step, rot_cam_from_icrs, camera, ref_icrs, x, y) - res) / _STEP
        delta, *_ = np.linalg.lstsq(jac, -res, rcond=None)
        params = params + delta
        if np.max(np.abs(delta)) < 1e-10:
            break
    rot = Rotation.from_rotvec(params[:3]) * rot_cam_from_icrs
    cam = camera if n_params == 3 else camera.with_focal(camera.fx * np.exp(params[3]))
    res = _residuals(np.zeros(3), rot, cam, ref_icrs, x, y).reshape(2, -1)
    return rot, cam, np.hypot(res[0], res[1])
