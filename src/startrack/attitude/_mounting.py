"""The mounting rotation between the camera and the spacecraft body.

Jacobs 1995 §1.3 (star sensor -> body) and Sease 2013 eq. 3.27 (Sease 2013 eqs. 3.24-3.27,
whose ``R_cam^T [a x]`` is not a frame change: a vector turns as ``v_body = C v_cam``,
a skew matrix as ``C [a x] C^T``). The mounting is ``rot_cam_from_body`` (constant), so

    rot_body_from_icrs = rot_cam_from_body.inv() * rot_cam_from_icrs
    v_body = rot_cam_from_body.inv().apply(v_cam)          (rates and axes alike)
    P_body = C^T P_cam C,    C = rot_cam_from_body.as_matrix()

and it can be estimated from simultaneous camera and body attitudes (e.g. a gyro-propagated
body attitude, or a fixed mount on the ground as in Fowler 2013 eq. 7.18) as the Markley average of
``rot_cam_from_icrs_k * rot_body_from_icrs_k.inv()``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ._averaging import average_rotations


def body_attitude(rot_cam_from_icrs: Rotation, rot_cam_from_body: Rotation) -> Rotation:
    """``rot_body_from_icrs`` from the camera attitude and the mounting."""
    return rot_cam_from_body.inv() * rot_cam_from_icrs


def camera_attitude(rot_body_from_icrs: Rotation, rot_cam_from_body: Rotation) -> Rotation:
    """``rot_cam_from_icrs`` from a body attitude and the mounting."""
    return rot_cam_from_body * rot_body_from_icrs


def to_body(vectors_cam: ArrayLike, rot_cam_from_body: Rotation) -> NDArray[np.float64]:
    """Camera-frame vectors (..., 3), e.g. an angular velocity, in body-frame components."""
    return rot_cam_from_body.inv().apply(np.asarray(vectors_cam, dtype=float))


def covariance_to_body(covariance_cam: ArrayLike, rot_cam_from_body: Rotation) -> NDArray[np.float64]:
    """A camera-frame covariance (..., 3, 3) of an attitude or rate error in body axes, ``C^T P C``."""
    cov = np.asarray(covariance_cam, dtype=float)
    if cov.shape[-2:] != (3, 3):
        raise InvalidInputError(f"covariance_cam must have shape (..., 3, 3), got {cov.shape}")
    matrix = rot_cam_from_body.as_matrix()
    return np.swapaxes(matrix, -1, -2) @ cov @ matrix


def estimate_mounting(
    rot_cam_from_icrs: Rotation, rot_body_from_icrs: Rotation, weights: ArrayLike | None = None
) -> Rotation:
    """``rot_cam_from_body`` from K simultaneous camera and body attitudes (stacks of K >= 1).

    The Markley average (:mod:`._averaging`) of the K single-epoch mountings, optionally
    weighted (e.g. by the inverse variance of each camera attitude).
    """
    cam = Rotation.from_quat(np.atleast_2d(rot_cam_from_icrs.as_quat()))
    body = Rotation.from_quat(np.atleast_2d(rot_body_from_icrs.as_quat()))
    if len(cam) != len(body):
        raise InvalidInputError(f"need as many body as camera attitudes, got {len(body)} and {len(cam)}")
    return average_rotations(cam * body.inv(), weights)
