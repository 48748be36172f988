"""Least-squares refinement of an attitude (and optionally the focal length) from matched stars.

Minimises the pixel residuals between detected stars and their catalog stars projected through
the camera, over a small rotation of the camera frame and, when it is free, the logarithm of the
focal length (fx and fy scale together). Gauss-Newton with the analytic Jacobian of the
projection; a few iterations suffice.

The fits run on rotation matrices (``matrix_cam_from_icrs``, (3, 3), mapping ICRS vectors to
camera vectors) with the Jacobian and residuals of all stars built by a few whole-array numpy
operations per step: on the few dozen stars of a solve, per-call overhead (scipy Rotation
objects, small linear-algebra calls) would cost more than the arithmetic. :func:`refine_pointing`
is the same fit for a Rotation.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import lapack
from scipy.spatial.transform import Rotation

from ..camera import Camera

_MAX_ITER = 6
_CONVERGED_PX = 1e-4
"""Stop when the step moves no image point by more than this (pixels)."""

_PERP_SIGN = np.array([[-1.0], [1.0]])
"""(-b, a) = (b, a) * _PERP_SIGN."""

_UNIT_TURN = np.array([[[0.0], [-1.0]], [[1.0], [0.0]]])
"""The constant parts (0, -1) and (1, 0) of du/dd_x and du/dd_y (see :func:`_system`), shape (2, 2, 1)."""


def _rodrigues(x: float, y: float, z: float) -> NDArray:
    """Rotation matrix (3, 3) of the rotation vector (x, y, z) (radians):
    ``cos t I + sin t [k]_x + (1 - cos t) k k^T`` with angle t and unit axis k."""
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-15:
        return np.eye(3)
    x, y, z = x / angle, y / angle, z / angle
    s, c = math.sin(angle), math.cos(angle)
    t = 2.0 * math.sin(0.5 * angle) ** 2  # 1 - cos, without the cancellation
    return np.array([[c + t * x * x, t * x * y - s * z, t * x * z + s * y],
                     [t * x * y + s * z, c + t * y * y, t * y * z - s * x],
                     [t * x * z - s * y, t * y * z + s * x, c + t * z * z]])


def _image_coords(camera: Camera, cam_vec: NDArray) -> tuple[NDArray, NDArray]:
    """Pinhole coordinates u = (a, b) = (v_x, v_y) / v_z of camera vectors (3, N) and the same
    through the camera's distortion, both (2, N)."""
    pinhole = cam_vec[:2] / cam_vec[2]
    if camera.has_distortion:
        return pinhole, np.array(camera._distort(*pinhole))
    return pinhole, pinhole


def _system(camera: Camera, focal: NDArray, cam_vec: NDArray, offset: NDArray, n_params: int) -> NDArray:
    """The least-squares system of a fit: rows (n_params + 1, 2N) holding the transposed
    Jacobian of the predicted pixels (x_0, ..., x_N-1, y_0, ..., y_N-1) of camera vectors
    (3, N) with respect to (small rotation of the camera frame, [ln f], [k1]) and, last, the
    residuals (detected minus predicted pixels). The camera gives the principal point and the
    distortion, ``focal`` (2, 1) the focal lengths (fx, fy) and ``offset`` (2, N) the detected
    positions minus the principal point. The product of the rows with their transpose holds
    the normal equations ``[[J^T J, J^T r], [r^T J, r^T r]]``.

    A rotation d moves a camera vector v to v + d x v; for the pinhole coordinates u = (a, b)
    that is du/dd_x = -b u - (0, 1), du/dd_y = a u + (1, 0) and du/dd_z = (-b, a), then
    through the distortion's 2 x 2 Jacobian and the focal lengths, which scale every x row by
    fx and every y row by fy (the residuals too, which are first computed in focal lengths).
    """
    pinhole, distorted = _image_coords(camera, cam_vec)
    perp = pinhole[::-1] * _PERP_SIGN  # (-b, a)
    rows = [perp[:, None] * pinhole + _UNIT_TURN, perp[None]]  # du / d rotation, (2, 2, N) and (1, 2, N)
    if distorted is not pinhole:
        daa, dab, dba, dbb = camera._distort_jacobian(*pinhole)
        d_rot = np.concatenate(rows)
        da, db = d_rot[:, 0], d_rot[:, 1]
        rows = [np.stack([daa * da + dab * db, dba * da + dbb * db], axis=1)]
    if n_params > 3:  # d / d ln f: fx and fy scale together
        rows.append(distorted[None])
    if n_params > 4:  # d / d k1 of x = cx + fx a (1 + k1 r^2 + ...)
        rows.append((pinhole * np.sum(pinhole * pinhole, axis=0))[None])
    rows.append((offset / focal - distorted)[None])
    system = np.concatenate(rows)
    system *= focal
    return system.reshape(n_params + 1, -1)


def _offset(camera: Camera, x: NDArray, y: NDArray) -> NDArray:
    """Detected positions (pixels, (N,) each) minus the principal point, shape (2, N)."""
    return np.array([x - camera.cx, y - camera.cy])


def _step(system: NDArray) -> list[float]:
    """The Gauss-Newton step (p floats) of a least-squares system (p + 1, M) from :func:`_system`:
    the normal equations by Cholesky, least squares if they are singular."""
    normal = system @ system.T
    _, step, info = lapack.dposv(normal[:-1, :-1], normal[:-1, -1])
    if info != 0:
        step = np.linalg.lstsq(system[:-1].T, system[-1], rcond=None)[0]
    return step.tolist()


def _moved_px(delta: list[float], camera: Camera, fx: float) -> float:
    """Largest image motion (pixels) a step causes, roughly: rotation times focal length ``fx``,
    plus the focal and k1 changes at the image corner."""
    corner = 0.5 * math.hypot(camera.width, camera.height)
    moved = max(abs(d) for d in delta[:3]) * fx * 2.0
    if len(delta) > 3:
        moved += abs(delta[3]) * corner
    if len(delta) > 4:
        moved += abs(delta[4]) * corner * (corner / fx) ** 2
    return moved


def _stepped(camera: Camera, focal: NDArray, delta: list[float]) -> tuple[Camera, NDArray]:
    """The camera and focal lengths (2, 1) after a step's ln f and k1 changes (those the step has)."""
    if len(delta) > 3:
        focal = focal * math.exp(delta[3])
    if len(delta) > 4:
        camera = camera.with_distortion(k1=camera.k1 + delta[4])
    return camera, focal


def fit_pose(matrix_cam_from_icrs: NDArray, camera: Camera, ref_icrs: NDArray, x: NDArray, y: NDArray, *,
             fit_focal: bool, fit_k1: bool = False) -> tuple[NDArray[np.float64], Camera, NDArray[np.float64]]:
    """Refine an attitude matrix (and focal length) to matched stars.

    Parameters
    ----------
    matrix_cam_from_icrs : ndarray, shape (3, 3)
        Starting attitude, the rotation matrix taking ICRS vectors to camera vectors.
    camera : Camera
        Starting camera; only its focal length (and k1) change when they are fitted.
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
    matrix, camera, residual_px
        The refined attitude matrix (3, 3) and camera and each star's pixel residual distance, shape (K,).
    """
    fit_focal = fit_focal and len(x) >= 3
    fit_k1 = fit_k1 and fit_focal and len(x) >= 8
    n_params = 3 + int(fit_focal) + int(fit_k1)
    ref_t, offset, focal = ref_icrs.T, _offset(camera, x, y), np.array([[camera.fx], [camera.fy]])
    matrix = matrix_cam_from_icrs
    for _ in range(_MAX_ITER):  # the focal lengths live in ``focal``; the camera gets them at the end
        delta = _step(_system(camera, focal, matrix @ ref_t, offset, n_params))
        matrix = _rodrigues(*delta[:3]) @ matrix
        camera, focal = _stepped(camera, focal, delta)
        if _moved_px(delta, camera, focal[0, 0]) < _CONVERGED_PX:
            break
    if fit_focal:
        camera = camera.with_focal(focal[0, 0], focal[1, 0])
    residual = offset - focal * _image_coords(camera, matrix @ ref_t)[1]
    return matrix, camera, np.hypot(*residual)


def refine_pointing(rot_cam_from_icrs: Rotation, camera: Camera, ref_icrs: NDArray, x: NDArray,
                    y: NDArray, *, fit_focal: bool,
                    fit_k1: bool = False) -> tuple[Rotation, Camera, NDArray[np.float64]]:
    """:func:`fit_pose` for an attitude given as a Rotation: (rotation, camera, residual_px (K,))."""
    matrix, camera, residual_px = fit_pose(rot_cam_from_icrs.as_matrix(), camera, ref_icrs, x, y,
                                           fit_focal=fit_focal, fit_k1=fit_k1)
    return Rotation.from_matrix(matrix), camera, residual_px


def leave_one_out_residuals(matrix_cam_from_icrs: NDArray, camera: Camera, ref_icrs: NDArray, x: NDArray,
                            y: NDArray, *, fit_focal: bool) -> NDArray[np.float64]:
    """How far (pixels, (K,)) each star lies from where a fit to the other stars puts it.

    At a converged fit (attitude matrix (3, 3) as in :func:`fit_pose`) with residuals r_i (2,)
    and Jacobian rows J_i (2, p), leaving star i out moves its residual to ``(I - H_ii)^-1 r_i``
    with the leverage block ``H_ii = J_i (J^T J)^-1 J_i^T`` (the linearised deleted residual;
    Cook and Weisberg 1982, "Residuals and Influence in Regression", §2.2). A wrong association
    pulls a few-star fit towards itself, so its own residual can be unremarkable while its
    deleted residual is not. Stars with a leverage block near singular (a fit that needs that
    star) get inf.
    """
    n_params = 3 + int(fit_focal and len(x) >= 3)
    focal = np.array([[camera.fx], [camera.fy]])
    system = _system(camera, focal, matrix_cam_from_icrs @ ref_icrs.T, _offset(camera, x, y), n_params)
    jac = system[:-1]
    _, spread, info = lapack.dposv(jac @ jac.T, jac)  # (J^T J)^-1 J^T, (p, 2K)
    if info != 0:
        return np.full(len(x), np.inf)
    keep_xx, keep_yy = 1.0 - np.sum((jac * spread).reshape(n_params, 2, -1), axis=0)  # I - H_ii, symmetric
    keep_xy = -np.sum(jac.reshape(n_params, 2, -1)[:, 0] * spread.reshape(n_params, 2, -1)[:, 1], axis=0)
    det = keep_xx * keep_yy - keep_xy * keep_xy
    rx, ry = system[-1].reshape(2, -1)
    out = np.full(len(x), np.inf)
    ok = det > 1e-9
    dx, dy = keep_yy * rx - keep_xy * ry, keep_xx * ry - keep_xy * rx
    out[ok] = np.hypot(dx[ok], dy[ok]) / det[ok]
    return out
