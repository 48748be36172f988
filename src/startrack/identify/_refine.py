"""Least-squares refinement of an attitude (and optionally the focal length) from matched stars.

Minimises the pixel residuals between detected stars and their catalog stars projected through
the camera, over a small rotation of the camera frame and, when they are free, the logarithm of the
focal length (fx and fy scale together), the logarithm of the pixel aspect fy / fx and the radial
distortion coefficients k1 and k2. Gauss-Newton with the analytic Jacobian of the
projection; a few iterations suffice.

The fits run on rotation matrices (``matrix_cam_from_icrs``, (3, 3), mapping ICRS vectors to
camera vectors) in compiled loops (:mod:`._pose_kernel` and :mod:`._match_kernel`, numba, loaded
on first use): on the few dozen stars of a solve, per-call overhead of numpy and scipy would
cost more than the arithmetic. :func:`warm_up_pose` compiles them before any timed work.
:func:`refine_pointing` is the same fit for a Rotation.
"""

from __future__ import annotations

import functools
import math
from types import ModuleType

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import UNDISTORT_MAX_ITER, UNDISTORT_TOL_PX, Camera
from ._parity import unmirrored

_MAX_ITER = 6
_CONVERGED_PX = 1e-4
"""Stop when the step moves no image point by more than this (pixels)."""


@functools.cache
def _kernel() -> ModuleType:
    """The compiled functions, :mod:`._pose_kernel` (numba is imported on first use)."""
    from . import _pose_kernel as pose_kernel

    return pose_kernel


@functools.cache
def _match_kernel() -> ModuleType:
    """The compiled pairing, cone and lens-inversion loops, :mod:`._match_kernel`."""
    from . import _match_kernel as match_kernel

    return match_kernel


def _plain(values: ArrayLike) -> NDArray[np.float64]:
    """``values`` as the one array type the kernels are compiled for: float64, C-contiguous,
    writeable (numba compiles another signature for each other layout or a read-only array)."""
    out = np.ascontiguousarray(values, dtype=np.float64)
    return out if out.flags.writeable else out.copy()


def _distortion(camera: Camera) -> NDArray[np.float64]:
    """The camera's distortion coefficients (k1, k2, k3, p1, p2), shape (5,)."""
    return np.array([camera.k1, camera.k2, camera.k3, camera.p1, camera.p2], dtype=np.float64)


def _offset(camera: Camera, x: NDArray, y: NDArray) -> NDArray[np.float64]:
    """Detected positions (pixels, (N,) each) minus the principal point, shape (2, N)."""
    return np.array([x - camera.cx, y - camera.cy], dtype=np.float64)


def free_flags(*, fit_focal: bool, fit_aspect: bool = False, fit_k1: bool = False,
               fit_k2: bool = False) -> NDArray[np.int64]:
    """The ``free`` flags (4,) of the compiled fit (:data:`.pose_kernel.FREE_FOCAL` order: ln f,
    ln(fy / fx), k1, k2)."""
    return np.array([fit_focal, fit_aspect, fit_k1, fit_k2], dtype=np.int64)


def _system(camera: Camera, focal: NDArray, cam_vec: NDArray, offset: NDArray, free: NDArray) -> NDArray:
    """The least-squares system of a fit (:func:`.pose_kernel.fill_system`), shape (p + 1, 2N).

    Rows: the transposed Jacobian of the predicted pixels (x_0, ..., x_N-1, y_0, ..., y_N-1) of
    camera vectors ``cam_vec`` (3, N) with respect to (small rotation of the camera frame (rad),
    then the parameters ``free`` (4,) flags: [ln f], [ln(fy / fx)], [k1], [k2]) and, last, the
    residuals (detected minus predicted pixels). The camera gives the distortion, ``focal``
    (2, 1) the focal lengths (fx, fy) in pixels and ``offset`` (2, N) the detected positions
    minus the principal point (pixels). The product of the rows with their transpose holds the
    normal equations ``[[J^T J, J^T r], [r^T J, r^T r]]``.
    """
    free = np.ascontiguousarray(free, dtype=np.int64)
    system = np.empty((3 + int(free.sum()) + 1, 2 * cam_vec.shape[1]))
    _kernel().fill_system(_plain(cam_vec), _plain(offset), float(focal[0, 0]), float(focal[1, 0]),
                          _distortion(camera), free, system)
    return system


MIN_STARS_FOCAL, MIN_STARS_ASPECT, MIN_STARS_K1, MIN_STARS_K2 = 3, 6, 8, 12
"""Fewest stars with which each parameter is fitted (below, it stays fixed): the rotation and the
focal length need three stars; every further parameter wants a few more stars than unknowns."""


def _usable_flags(n_stars: int, fit_focal: bool, fit_aspect: bool, fit_k1: bool,
                  fit_k2: bool) -> NDArray[np.int64]:
    """The flags a fit to ``n_stars`` stars can afford (each parameter needs the ones before it)."""
    focal = fit_focal and n_stars >= MIN_STARS_FOCAL
    k1 = fit_k1 and focal and n_stars >= MIN_STARS_K1
    return free_flags(fit_focal=focal, fit_aspect=fit_aspect and focal and n_stars >= MIN_STARS_ASPECT,
                      fit_k1=k1, fit_k2=fit_k2 and k1 and n_stars >= MIN_STARS_K2)


def fit_pose(matrix_cam_from_icrs: NDArray, camera: Camera, ref_icrs: NDArray, x: NDArray, y: NDArray, *,
             fit_focal: bool, fit_k1: bool = False, fit_aspect: bool = False,
             fit_k2: bool = False) -> tuple[NDArray[np.float64], Camera, NDArray[np.float64]]:
    """Refine an attitude matrix (and focal length, pixel aspect, radial distortion) to matched stars.

    Gauss-Newton (:func:`.pose_kernel.fit`): at most ``_MAX_ITER`` steps, until a step moves no
    image point by more than ``_CONVERGED_PX``; a step whose normal equations are singular is the
    minimum-norm least-squares one.

    Parameters
    ----------
    matrix_cam_from_icrs : ndarray, shape (3, 3)
        Starting attitude, the rotation matrix taking ICRS vectors to camera vectors.
    camera : Camera
        Starting camera; only its focal lengths (and k1, k2) change when they are fitted.
    ref_icrs : ndarray, shape (K, 3)
        ICRS unit vectors of the matched catalog stars.
    x, y : ndarray, shape (K,)
        Detected positions (pixels) of the same stars.
    fit_focal : bool
        Also fit the focal length, fx and fy together (needs at least 3 stars; otherwise it
        stays fixed).
    fit_k1 : bool
        Also fit the first radial distortion coefficient (with the focal length; needs at least
        8 stars). For photographs from lenses nobody calibrated.
    fit_aspect : bool
        Also fit the pixel aspect, fy against fx (with the focal length; needs at least 6 stars).
    fit_k2 : bool
        Also fit the second radial coefficient (with k1; needs at least 12 stars): wide lenses.

    Returns
    -------
    matrix, camera, residual_px
        The refined attitude matrix (3, 3) and camera and each star's pixel residual distance, shape (K,).
    """
    mirrored = camera.mirrored
    camera, x = unmirrored(camera, x)
    free = _usable_flags(len(x), fit_focal, fit_aspect, fit_k1, fit_k2)
    corner = 0.5 * math.hypot(camera.width, camera.height)
    matrix, fx, fy, k1, k2, residual = _kernel().fit(
        _plain(matrix_cam_from_icrs), _plain(ref_icrs), _plain(x), _plain(y), float(camera.fx), float(camera.fy),
        float(camera.cx), float(camera.cy), _distortion(camera), free, corner, _MAX_ITER, _CONVERGED_PX)
    if free[2] or free[3]:
        camera = camera.with_distortion(k1=k1, k2=k2)
    if free[0] or free[1]:
        camera = camera.with_focal(fx, fy)
    return matrix, camera.mirror_image() if mirrored else camera, residual


def refine_pointing(rot_cam_from_icrs: Rotation, camera: Camera, ref_icrs: NDArray, x: NDArray,
                    y: NDArray, *, fit_focal: bool, fit_k1: bool = False,
                    fit_aspect: bool = False) -> tuple[Rotation, Camera, NDArray[np.float64]]:
    """:func:`fit_pose` for an attitude given as a Rotation: (rotation, camera, residual_px (K,))."""
    matrix, camera, residual_px = fit_pose(rot_cam_from_icrs.as_matrix(), camera, ref_icrs, x, y,
                                           fit_focal=fit_focal, fit_k1=fit_k1, fit_aspect=fit_aspect)
    return Rotation.from_matrix(matrix), camera, residual_px


def leave_one_out_residuals(matrix_cam_from_icrs: NDArray, camera: Camera, ref_icrs: NDArray, x: NDArray,
                            y: NDArray, *, fit_focal: bool, fit_aspect: bool = False) -> NDArray[np.float64]:
    """How far (pixels, (K,)) each star lies from where a fit to the other stars puts it.

    At a converged fit (attitude matrix (3, 3) as in :func:`fit_pose`, ICRS unit vectors
    ``ref_icrs`` (K, 3), detected pixels ``x``, ``y`` (K,)) with residuals r_i (2,) and Jacobian
    rows J_i (2, p), leaving star i out moves its residual to ``(I - H_ii)^-1 r_i`` with the
    leverage block ``H_ii = J_i (J^T J)^-1 J_i^T`` (the linearised deleted residual; Cook and
    Weisberg 1982, "Residuals and Influence in Regression", §2.2). A wrong association pulls a
    few-star fit towards itself, so its own residual can be unremarkable while its deleted
    residual is not. Stars with a leverage block near singular (a fit that needs that star) get
    inf; all do when J^T J is singular. The parameters are those :func:`fit_pose` fits with
    the same flags (focal length, pixel aspect).
    """
    camera, x = unmirrored(camera, x)
    free = _usable_flags(len(x), fit_focal, fit_aspect, False, False)
    focal = np.array([[camera.fx], [camera.fy]])
    cam_vec = _plain(matrix_cam_from_icrs) @ _plain(ref_icrs).T
    return _kernel().deleted_residuals(_system(camera, focal, cam_vec, _offset(camera, x, y), free))


def wahba_equal_weights(observed: NDArray, reference: NDArray) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Attitude of equally weighted vector pairs by Davenport's q-method (Huffman 2006 §6.1.3;
    :func:`.pose_kernel.q_method`, the single-problem, compiled form of
    :func:`startrack.attitude._qmethod.q_method_quaternions`).

    Parameters
    ----------
    observed, reference : ndarray, shape (N, 3)
        Unit vectors, camera frame and ICRS.

    Returns
    -------
    quat, matrix : ndarray, shapes (4,) and (3, 3)
        The rotation R with ``R reference_i ~ observed_i`` as a scalar-last quaternion and a matrix.
    """
    return _kernel().q_method(_plain(observed), _plain(reference))


def match_predicted(ref_icrs: NDArray, matrix_cam_from_icrs: NDArray, camera: Camera, x: NDArray, y: NDArray,
                    radius_px: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Image stars matched to the catalog stars an attitude predicts inside the image, closest pairs
    first and each star once (:func:`.verify.match_nearest`'s rule; compiled,
    :func:`.match_kernel.rematch_pairs`).

    Parameters
    ----------
    ref_icrs : ndarray, shape (S, 3)
        ICRS unit vectors of the catalog stars.
    matrix_cam_from_icrs : ndarray, shape (3, 3)
        The attitude, taking ICRS vectors to camera vectors.
    camera : Camera
    x, y : ndarray, shape (N,)
        Image stars (pixels).
    radius_px : float
        Largest distance of a pair (pixels).

    Returns
    -------
    image_index, catalog_index : ndarray, shape (K,) each
        Indices into ``x`` and into ``ref_icrs``, closest pair first.
    """
    camera, x = unmirrored(camera, x)
    return _match_kernel().rematch_pairs(_plain(ref_icrs), _plain(matrix_cam_from_icrs), float(camera.fx),
                                   float(camera.fy), float(camera.cx), float(camera.cy), _distortion(camera),
                                   float(camera.width), float(camera.height), _plain(x), _plain(y), float(radius_px))



def predicted_pairs(ref_icrs: NDArray, matrix_cam_from_icrs: NDArray, camera: Camera, x: NDArray, y: NDArray,
                    radius_px: float) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64], int]:
    """:func:`match_predicted` with the squared distance of each pair (K,) in px^2 and the number
    of catalog stars predicted inside the image (one compiled call,
    :func:`.match_kernel.predicted_pairs`): the pairs of a match within a radius r up to
    ``radius_px`` are those with a squared distance of at most r * r, in the same order."""
    camera, x = unmirrored(camera, x)
    return _match_kernel().predicted_pairs(_plain(ref_icrs), _plain(matrix_cam_from_icrs), float(camera.fx),
                                           float(camera.fy), float(camera.cx), float(camera.cy), _distortion(camera),
                                           float(camera.width), float(camera.height), _plain(x), _plain(y),
                                           float(radius_px))

def pixel_vectors(camera: Camera, x: NDArray, y: NDArray) -> NDArray[np.float64]:
    """:meth:`Camera.pixel_to_vector <startrack.camera.Camera.pixel_to_vector>` of finite pixel
    coordinates ``x``, ``y`` (N,) in one compiled call (:func:`.match_kernel.pixel_vectors`; the
    same Newton iterations and tolerance, point by point): unit camera vectors (N, 3), NaN where
    the lens model cannot be inverted."""
    camera, x = unmirrored(camera, x)
    return _match_kernel().pixel_vectors(_plain(x), _plain(y), float(camera.fx), float(camera.fy), float(camera.cx),
                                   float(camera.cy), _distortion(camera), UNDISTORT_TOL_PX / max(camera.fx, camera.fy),
                                   UNDISTORT_MAX_ITER)


def stars_in_cone(vectors: NDArray, count: int, axis: NDArray, radius_rad: float, neighbour_rad: NDArray,
                  min_neighbour_rad: float) -> NDArray[np.int64]:
    """Indices (ascending) among the first ``count`` of the unit vectors ``vectors`` (S, 3) of
    those within ``radius_rad`` of the unit vector ``axis`` (3,) whose ``neighbour_rad`` (S,) is at
    least ``min_neighbour_rad`` (one compiled pass, :func:`.match_kernel.cone_stars`)."""
    return _match_kernel().cone_stars(vectors, int(count), _plain(axis), math.cos(min(radius_rad, math.pi)),
                                neighbour_rad, float(min_neighbour_rad))


def solution_terms(observed: NDArray, reference: NDArray, sigma_rad: float) -> tuple:
    """The attitude of equally weighted vector pairs (:func:`wahba_equal_weights`) with what a
    solution reports of it, in one compiled call (:func:`.pose_kernel.solution_terms`).

    Parameters
    ----------
    observed, reference : ndarray, shape (N, 3)
        Unit vectors, camera frame and ICRS (N >= 3, not all on one great circle).
    sigma_rad : float
        1-sigma error of each observed direction per axis (radians).

    Returns
    -------
    quat : ndarray, shape (4,)
        Scalar-last quaternion of R with ``R reference_i ~ observed_i``.
    matrix : ndarray, shape (3, 3)
        R.
    residual_rad : ndarray, shape (N,)
        Angle between ``R reference_i`` and ``observed_i`` (radians, the stable atan2 form).
    covariance_rad2 : ndarray, shape (3, 3)
        QUEST covariance of the attitude error in the camera frame
        (:func:`startrack.attitude._covariance.covariance_batch`).
    radec_roll : (float, float, float)
        Boresight RA, Dec and roll (radians, :func:`startrack.frames.radec_roll_from_rotation`).
    """
    return _kernel().solution_terms(_plain(observed), _plain(reference), float(sigma_rad))


@functools.cache
def warm_up_pose() -> None:
    """Compile (or load from the disk cache) the kernels of :func:`fit_pose`,
    :func:`leave_one_out_residuals`, :func:`wahba_equal_weights`, :func:`match_predicted`,
    :func:`predicted_pairs`, :func:`pixel_vectors`, :func:`stars_in_cone`, :func:`solution_terms` and the cone
    queries of :class:`.verify.SkyBands`, so that a solve's time does not include it. Free after the first call."""
    camera = Camera(width=64, height=64, fx=100.0, k1=1e-3)
    x, y = np.array([10.0, 50.0, 30.0, 20.0]), np.array([10.0, 20.0, 50.0, 40.0])
    ref = camera.pixel_to_vector(x, y)  # attitude: identity
    matrix, camera, _ = fit_pose(np.eye(3), camera, ref, x, y, fit_focal=True)
    leave_one_out_residuals(matrix, camera, ref, x, y, fit_focal=True)
    wahba_equal_weights(camera.pixel_to_vector(x, y), ref)
    match_predicted(ref, matrix, camera, x, y, 1.0)
    predicted_pairs(ref, matrix, camera, x, y, 1.0)
    pixel_vectors(camera, x, y)
    stars_in_cone(ref, len(ref), matrix[2], 0.1, np.zeros(len(ref)), 0.0)
    from ._verify import SkyBands  # the cone queries of the confirmation and the catalog choice

    bands = SkyBands(ref)
    bands.query_ball_point(matrix[2], 0.1)
    bands.brightest_in_cone(len(ref), matrix[2], 0.1, np.zeros(len(ref)), 0.0)
    solution_terms(camera.pixel_to_vector(x, y), ref, 1e-4)
