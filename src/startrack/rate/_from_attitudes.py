"""Angular rate from two or more attitudes.

Samaan 2002 step 6 eq. 3 (Samaan 2002 Eq. 1–3) and Sease 2013 eqs. 3.24-3.27 (§1.20): with
``Delta = C(t + dt) C(t)^T`` (C = rot_cam_from_icrs as a matrix), the kinematics
``dC/dt = -[omega x] C`` give

    [omega x] ~ (I - Delta) / dt                    (Samaan 2002, first order)
    omega = -log(Delta) / dt = -rotvec(Delta) / dt  (exact for a constant rate)

The first-order matrix is only nearly skew-symmetric; its skew part is taken (Sease 2013 item
19). The exact form is the default; Sease 2013's principal angle and axis (``Phi = acos((tr Delta
- 1) / 2)``, ``[a x] = (Delta - Delta^T) / (2 sin Phi)``) are the same log map, computed stably
by scipy.

With K > 2 attitudes, a constant rate is fitted: the rotation vectors ``phi_k =
rotvec(C_k C_ref^T)`` relative to the middle attitude are exactly linear in time for a constant
rate, ``phi_k = phi_0 - omega (t_k - t_ref)``, so omega is the least-squares slope (with an
intercept that absorbs the reference attitude's own error). Valid while the rotation over the
window stays below 180 degrees.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ..results import Status
from ._estimate import RateEstimate, failed

METHOD = "attitudes"


def _skew_part_vex(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """vex of the skew-symmetric part of matrices (..., 3, 3)."""
    skew = 0.5 * (matrix - np.swapaxes(matrix, -1, -2))
    return np.stack([skew[..., 2, 1], skew[..., 0, 2], skew[..., 1, 0]], axis=-1)


def rate_between(
    rot_before: Rotation, rot_after: Rotation, dt_s: ArrayLike, *, first_order: bool = False
) -> NDArray[np.float64]:
    """Camera-frame rate (rad/s), shape (3,) or (M, 3), turning ``rot_before`` into ``rot_after``.

    ``first_order=True`` gives Samaan 2002's eq. 3, ``vex(skew((I - Delta) / dt))``, which is biased
    by ~|omega dt|^2 / 6 relative; the default is the exact log map.
    """
    dt = np.asarray(dt_s, dtype=float)
    if not np.all(np.isfinite(dt) & (dt != 0.0)):
        raise InvalidInputError(f"dt_s must be finite and non-zero seconds, got {dt_s!r}")
    delta = rot_after * rot_before.inv()
    if first_order:
        return _skew_part_vex(np.eye(3) - delta.as_matrix()) / dt[..., None]
    return -delta.as_rotvec() / dt[..., None]


def _pair_covariance(delta: Rotation, cov_a, cov_b, dt: float) -> NDArray[np.float64]:
    """(P_b + D P_a D^T) / dt^2: errors of both attitudes, in the later camera frame."""
    d = delta.as_matrix()
    return (np.asarray(cov_b) + d @ np.asarray(cov_a) @ d.T) / dt**2


def _checked_times(rotations: Rotation, times_s: ArrayLike) -> NDArray[np.float64]:
    times = np.asarray(times_s, dtype=float)
    if rotations.single or times.shape != (len(rotations),) or not np.all(np.isfinite(times)):
        raise InvalidInputError(
            f"times_s must be finite with one time per rotation (a stack of K), got shape {times.shape}"
        )
    if np.any(np.diff(times) <= 0.0):
        raise InvalidInputError("times_s must be strictly increasing")
    return times


def rate_from_attitudes(
    rotations: Rotation, times_s: ArrayLike, covariances_rad2: ArrayLike | None = None
) -> RateEstimate:
    """Constant camera-frame rate fitted to K >= 2 attitudes (module docstring).

    Parameters
    ----------
    rotations : Rotation
        Stack of K attitudes ``rot_cam_from_icrs`` of the same camera.
    times_s : array_like, shape (K,)
        Their times, seconds, strictly increasing.
    covariances_rad2 : array_like, shape (K, 3, 3), optional
        Attitude covariances (camera frame, rad^2). With them the estimate carries a covariance
        (for K > 2 from the mean variance per attitude; without them, for K > 2, from the
        scatter of the fit).

    Returns
    -------
    RateEstimate
        TOO_FEW_STARS status (no rate) for fewer than 2 attitudes.
    """
    if rotations.single or len(rotations) < 2:
        return failed(Status.TOO_FEW_STARS, "a rate needs at least two attitudes", METHOD)
    times = _checked_times(rotations, times_s)
    covs = None if covariances_rad2 is None else np.asarray(covariances_rad2, dtype=float)
    if covs is not None and covs.shape != (len(rotations), 3, 3):
        raise InvalidInputError(f"covariances_rad2 must have shape ({len(rotations)}, 3, 3), got {covs.shape}")
    if len(rotations) == 2:
        dt = times[1] - times[0]
        omega = rate_between(rotations[0], rotations[1], dt)
        cov = None if covs is None else _pair_covariance(rotations[1] * rotations[0].inv(), covs[0], covs[1], dt)
        return RateEstimate(Status.OK, omega_rad_s=omega, covariance_rad2_s2=cov, method=METHOD)
    return _fit_constant_rate(rotations, times, covs)


def _fit_constant_rate(rotations: Rotation, times, covs) -> RateEstimate:
    """Least-squares slope of the rotation vectors relative to the middle attitude."""
    mid = len(rotations) // 2
    phi = (rotations * rotations[mid].inv()).as_rotvec()
    dt = times - times.mean()
    slope = -(dt @ (phi - phi.mean(axis=0))) / (dt @ dt)
    if covs is not None:
        var = float(np.mean(np.trace(covs, axis1=1, axis2=2))) / 3.0
        cov = np.eye(3) * var / (dt @ dt)
    else:
        fit = phi.mean(axis=0) - np.outer(dt, slope)
        dof = max(len(rotations) - 2, 1)
        cov = np.diag(np.sum((phi - fit) ** 2, axis=0) / dof / (dt @ dt))
    return RateEstimate(Status.OK, omega_rad_s=slope, covariance_rad2_s2=cov, method=METHOD)
