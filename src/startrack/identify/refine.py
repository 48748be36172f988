"""Least-squares refinement of an attitude (and optionally the focal length) from matched stars.

Minimises the pixel residuals between detected stars and their catalog stars projected through
the camera, over a small rotation of the camera frame and, when it is free, the logarithm of the
focal length (fx and fy scale together). Gauss-Newton with the analytic Jacobian of
:meth:`startrack.camera.Camera.project_with_jacobian`; a few iterations suffice.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera

_MAX_ITER = 6
_CONVERGED_PX = 1e-4
"""Stop when the step moves no image point by more than this (pixels)."""


def _rodrigues(rotvec: NDArray) -> NDArray:
    """Rotation matrix of a rotation vector (radians)."""
    angle = math.sqrt(float(rotvec @ rotvec))
    if angle < 1e-15:
        return np.eye(3)
    kx, ky, kz = rotvec / angle
    k = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def _jacobian(camera: Camera, cam_vec: NDArray, n_params: int) -> tuple[NDArray, NDArray, NDArray]:
    """Pixels (x, y) of camera vectors (N, 3) and the Jacobian (2N, n_params) of (x0, y0, x1, ...)
    with respect to (small rotation of the camera frame, [ln f], [k1]).

    A rotation d moves a camera vector v to v + d x v; for the pinhole coordinates a = v_x / v_z,
    b = v_y / v_z that is da/dd = (-a b, 1 + a^2, -b) and db/dd = (-(1 + b^2), a b, a), then
    through the distortion's 2 x 2 Jacobian and the focal lengths.
    """
    inv_z = 1.0 / cam_vec[:, 2]
    a, b = cam_vec[:, 0] * inv_z, cam_vec[:, 1] * inv_z
    da = np.column_stack([-a * b, 1.0 + a * a, -b])
    db = np.column_stack([-(1.0 + b * b), a * b, a])
    if camera.has_distortion:
        daa, dab, dba, dbb = camera._distort_jacobian(a, b)
        da, db = daa[:, None] * da + dab[:, None] * db, dba[:, None] * da + dbb[:, None] * db
        ad, bd = camera._distort(a, b)
    else:
        ad, bd = a, b
    x, y = camera.cx + camera.fx * ad, camera.cy + camera.fy * bd
    jac = np.empty((a.size, 2, n_params))
    jac[:, 0, :3], jac[:, 1, :3] = camera.fx * da, camera.fy * db
    if n_params > 3:  # d / d ln f: fx and fy scale together
        jac[:, 0, 3], jac[:, 1, 3] = x - camera.cx, y - camera.cy
    if n_params > 4:  # d / d k1 of x = cx + fx a (1 + k1 r^2 + ...)
        r2 = a * a + b * b
        jac[:, 0, 4], jac[:, 1, 4] = camera.fx * a * r2, camera.fy * b * r2
    return x, y, jac.reshape(-1, n_params)


def _step(matrix: NDArray, camera: Camera, ref_icrs: NDArray, x: NDArray, y: NDArray, n_params: int) -> NDArray:
    """One Gauss-Newton step for the parameters (rotation vector, [ln f], [k1])."""
    px, py, jac = _jacobian(camera, ref_icrs @ matrix.T, n_params)
    res = np.column_stack([px - x, py - y]).reshape(-1)
    try:
        return np.linalg.solve(jac.T @ jac, -(jac.T @ res))
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(jac, -res, rcond=None)[0]


def _moved_px(delta: NDArray, camera: Camera) -> float:
    """Largest image motion (pixels) a step causes, roughly: rotation times focal length, plus
    the focal and k1 changes at the image corner."""
    corner = 0.5 * math.hypot(camera.width, camera.height)
    moved = float(np.max(np.abs(delta[:3]))) * camera.fx * 2.0
    if delta.size > 3:
        moved += abs(float(delta[3])) * corner
    if delta.size > 4:
        moved += abs(float(delta[4])) * corner * (corner / camera.fx) ** 2
    return moved


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
    n_params = 3 + int(fit_focal) + int(fit_k1)
    for _ in range(_MAX_ITER):
        delta = _step(matrix, camera, ref_icrs, x, y, n_params)
        matrix = _rodrigues(delta[:3]) @ matrix
        if fit_focal:
            camera = camera.with_focal(camera.fx * math.exp(delta[3]))
        if fit_k1:
            camera = camera.with_distortion(k1=camera.k1 + delta[4])
        if _moved_px(delta, camera) < _CONVERGED_PX:
            break
    px, py = camera.vector_to_pixel(ref_icrs @ matrix.T)
    return Rotation.from_matrix(matrix), camera, np.hypot(px - x, py - y)


def leave_one_out_residuals(rot_cam_from_icrs: Rotation, camera: Camera, ref_icrs: NDArray, x: NDArray,
                            y: NDArray, *, fit_focal: bool) -> NDArray[np.float64]:
    """How far (pixels, (K,)) each star lies from where a fit to the other stars puts it.

    At a converged fit with residuals r_i (2,) and Jacobian rows J_i (2, p), leaving star i out
    moves its residual to ``(I - H_ii)^-1 r_i`` with the leverage block
    ``H_ii = J_i (J^T J)^-1 J_i^T`` (the linearised deleted residual; Cook and Weisberg 1982,
    "Residuals and Influence in Regression", §2.2). A wrong association pulls a few-star fit
    towards itself, so its own residual can be unremarkable while its deleted residual is not.
    Stars with a leverage block near singular (a fit that needs that star) get inf.
    """
    fit_focal = fit_focal and len(x) >= 3
    n_params = 3 + int(fit_focal)
    px, py, jac = _jacobian(camera, ref_icrs @ rot_cam_from_icrs.as_matrix().T, n_params)
    res = np.column_stack([px - x, py - y])
    blocks = jac.reshape(-1, 2, n_params)
    try:
        inv_normal = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full(len(x), np.inf)
    leverage = blocks @ inv_normal @ blocks.transpose(0, 2, 1)
    keep = np.eye(2) - leverage
    det = keep[:, 0, 0] * keep[:, 1, 1] - keep[:, 0, 1] * keep[:, 1, 0]
    out = np.full(len(x), np.inf)
    ok = det > 1e-9
    out[ok] = np.linalg.norm(np.linalg.solve(keep[ok], res[ok][..., None])[..., 0], axis=1)
    return out
