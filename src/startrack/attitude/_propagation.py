"""Attitude kinematics: propagating an attitude with an angular velocity, and chaining
relative attitudes with their error growth.

Convention: ``A = rot_cam_from_icrs`` maps ICRS vectors into the camera frame, and the camera
turns with angular velocity omega (rad/s) relative to ICRS. With omega in camera components

    dA/dt = -[omega x] A,        A(t + dt) = exp(-[omega x] dt) A(t)    (constant omega)

and with omega in ICRS components (an inertially fixed axis, e.g. the Earth's spin for a camera
on the ground, Fowler 2013 eq. 7.14) ``A(t + dt) = A(t) exp(-[omega_icrs x] dt)``. The closed
form is exact for a constant omega (Sease 2013 eq. 2.12: the quaternion
kinematics ``dq/dt = 1/2 Omega(omega) q`` integrated exactly; :func:`quaternion_derivative` is
that equation in scipy's scalar-last active quaternions, for tests and integrators).

Relative attitude (Huffman 2006 §7.2): ``rot_j = delta_ij * rot_i`` with
``delta_ij = rot_cam_j_from_cam_i``; an error e_i (rad, camera frame i) becomes ``delta_ij e_i``
in frame j and adds to the error of delta_ij, so covariances add,
``P_j = delta_ij P_i delta_ij^T + P_ij``, and the angle error grows in quadrature
(``eps_j^2 = eps_i^2 + eps_ij^2``, the seed's eq. 7.1).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError, as_float_array, check_choice, check_instance
from ._linalg import quat_product

FRAMES = ("camera", "icrs")


MAX_TURN_RAD = 1e9
"""The largest angle a propagation turns through (rad): float64's spacing at 1e9 rad is 1.2e-7 rad,
so the attitude keeps a sub-microradian accuracy up to it (160 million turns); beyond about 1e300
the rotation vector overflows."""


def _omega(value: ArrayLike, name: str = "omega_rad_s") -> NDArray[np.float64]:
    arr = as_float_array(value, name)
    if arr.shape[-1:] != (3,) or not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"{name} must be finite with shape (3,) or (K, 3) (rad/s), got {arr.shape}")
    return arr


def propagate(
    rot_cam_from_icrs: Rotation, omega_rad_s: ArrayLike, dt_s: ArrayLike, *, frame: str = "camera"
) -> Rotation:
    """The attitude after turning at a constant angular velocity for ``dt_s``.

    Parameters
    ----------
    rot_cam_from_icrs : Rotation
        Attitude at the start (single, or a stack broadcasting against ``dt_s``).
    omega_rad_s : array_like, shape (3,)
        Angular velocity of the camera relative to ICRS, rad/s, in ``frame`` components.
    dt_s : float or array_like, shape (K,)
        Time steps, seconds (negative goes back in time); an array gives a stack of K attitudes.
    frame : {"camera", "icrs"}
        The frame of omega's components.

    Returns
    -------
    Rotation
        ``exp(-[omega x] dt) A`` (camera) or ``A exp(-[omega x] dt)`` (icrs).
    """
    check_instance(rot_cam_from_icrs, Rotation, "rot_cam_from_icrs")
    omega = _omega(omega_rad_s)
    dt = as_float_array(dt_s, "dt_s")
    if not np.all(np.isfinite(dt)) or dt.ndim > 1:
        raise InvalidInputError(f"dt_s must be a finite number or 1-D array of seconds, got {dt_s!r}")
    frame = check_choice(frame, FRAMES, "frame")
    angle = float(np.max(np.linalg.norm(omega) * np.abs(dt), initial=0.0))
    if not angle <= MAX_TURN_RAD:
        raise InvalidInputError(f"omega_rad_s * dt_s turns through {angle:.3g} rad, more than the {MAX_TURN_RAD:g} "
                                "rad whose remainder modulo a turn float64 still holds to a microradian")
    turn = Rotation.from_rotvec(-omega * dt[..., None])
    return turn * rot_cam_from_icrs if frame == "camera" else rot_cam_from_icrs * turn


def propagate_steps(
    rot_cam_from_icrs: Rotation, omega_rad_s: ArrayLike, dt_s: ArrayLike
) -> Rotation:
    """Attitudes (K + 1) after K steps of piecewise-constant camera-frame rates (K, 3) over dt_s (K,)."""
    omega = _omega(omega_rad_s)
    dt = np.broadcast_to(np.asarray(dt_s, dtype=float), omega.shape[:1])
    steps = Rotation.from_rotvec(-omega * dt[:, None])
    out = [rot_cam_from_icrs]
    for step in steps:
        out.append(step * out[-1])
    return Rotation.concatenate(out)


def quaternion_derivative(quat: ArrayLike, omega_rad_s: ArrayLike) -> NDArray[np.float64]:
    """dq/dt (..., 4) of the scalar-last quaternion of ``rot_cam_from_icrs`` (camera-frame omega).

    ``dq/dt = 1/2 (-omega, 0) (x) q`` (Hamilton product), the kinematics of Sease 2013 eq. 2.12 /
    Fowler 2013 eq. A.12 rewritten for active rotations with ``dA/dt = -[omega x] A``.
    """
    q = np.asarray(quat, dtype=float)
    omega = _omega(omega_rad_s)
    pure = np.concatenate([-omega, np.zeros(omega.shape[:-1] + (1,))], axis=-1)
    return 0.5 * quat_product(np.broadcast_to(pure, np.broadcast_shapes(pure.shape, q.shape)), q)


def relative_attitude(rot_from: Rotation, rot_to: Rotation) -> Rotation:
    """``rot_cam_j_from_cam_i = rot_to * rot_from.inv()`` between two attitudes of the same camera."""
    return rot_to * rot_from.inv()


def chain_relative(
    rot_start: Rotation,
    relative: Rotation,
    cov_start_rad2: ArrayLike | None = None,
    relative_cov_rad2: ArrayLike | None = None,
) -> tuple[Rotation, NDArray[np.float64] | None]:
    """Chain K relative attitudes onto a start attitude, with the covariance growth.

    Parameters
    ----------
    rot_start : Rotation
        Attitude of frame 0 (single).
    relative : Rotation
        Stack of K relative attitudes, ``relative[k] = rot_cam_{k+1}_from_cam_k``.
    cov_start_rad2 : array_like, shape (3, 3), optional
        Covariance of the start attitude (camera frame 0, rad^2); zero if omitted.
    relative_cov_rad2 : array_like, shape (K, 3, 3) or (3, 3), optional
        Covariance of each relative attitude (in camera frame k + 1, rad^2).

    Returns
    -------
    rotations : Rotation
        The K + 1 attitudes ``rot_{k+1} = relative[k] * rot_k``.
    covariances : ndarray, shape (K + 1, 3, 3) or None
        ``P_{k+1} = D_k P_k D_k^T + Q_k`` (module docstring); None when neither covariance given.
    """
    steps = Rotation.from_quat(np.atleast_2d(relative.as_quat()))
    count = len(steps)
    rotations = [rot_start]
    for step in steps:
        rotations.append(step * rotations[-1])
    if cov_start_rad2 is None and relative_cov_rad2 is None:
        return Rotation.concatenate(rotations), None
    p = np.zeros((3, 3)) if cov_start_rad2 is None else np.asarray(cov_start_rad2, dtype=float)
    q = np.zeros((count, 3, 3)) if relative_cov_rad2 is None else np.asarray(relative_cov_rad2, dtype=float)
    q = np.broadcast_to(q, (count, 3, 3))
    covs = [p]
    for matrix, q_k in zip(steps.as_matrix(), q, strict=True):
        covs.append(matrix @ covs[-1] @ matrix.T + q_k)
    return Rotation.concatenate(rotations), np.stack(covs)
