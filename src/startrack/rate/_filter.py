"""A constant-rate attitude filter over a sequence of frames (error-state Kalman filter).

Samaan 2002 step 6 suggests filtering the frame-to-frame rate (Samaan 2002 Eq. 1–3: "optionally
filter, e.g. with an alpha-beta or a Kalman filter"); Jacobs 1995's predictor (§4.1.8) extrapolates
each angle with fixed coefficients. This is the small multiplicative filter both point to: the
state is the attitude ``A = rot_cam_from_icrs`` and the camera-frame rate omega, the error state
``x = (dtheta, domega)`` with ``A_true = exp(dtheta) A`` (camera frame), and over a step dt

    A- = exp(-[omega x] dt) A,     dtheta- = E dtheta - dt domega,   E = exp(-[omega x] dt)
    P- = F P F^T + Q,              F = [[E, -dt I], [0, I]],  Q from a rate random walk

An attitude measurement (covariance R, camera frame) updates with ``z = rotvec(A_meas A-^T)``
and H = [I 0]; a rate measurement (e.g. from a streaked frame, :mod:`._streak_rate`) with
``z = omega_meas - omega`` and H = [0 I]. Attitude and rate outputs follow the conventions of
:mod:`._estimate`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError, require
from ..results import Status
from ._estimate import RateEstimate

METHOD = "filter"


@dataclass(frozen=True)
class FilterState:
    """The filter's estimate after an update: attitude, rate and the 6 x 6 error covariance."""

    time_s: float
    rotation: Rotation
    omega_rad_s: NDArray[np.float64]
    covariance: NDArray[np.float64]

    def rate(self) -> RateEstimate:
        """The rate part as a :class:`RateEstimate`."""
        return RateEstimate(Status.OK, omega_rad_s=self.omega_rad_s.copy(),
                            covariance_rad2_s2=self.covariance[3:, 3:].copy(), method=METHOD)


def _cov3(value: ArrayLike, name: str) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=float)
    if arr.shape == ():
        arr = np.eye(3) * arr
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"{name} must be a variance or a (3, 3) covariance, got shape {arr.shape}")
    return arr


class RateFilter:
    """Error-state Kalman filter of attitude and constant rate (module docstring).

    Parameters
    ----------
    rate_noise_rad_s2 : float
        Rate random-walk density: the rate may drift by ``rate_noise * sqrt(dt)`` rad/s per step
        (rad / s^1.5). Zero for a truly constant rate.
    initial_rate_sigma_rad_s : float
        1-sigma of the initial rate (rad/s) when the filter starts from one attitude.
    """

    def __init__(self, rate_noise_rad_s2: float = 1e-5, initial_rate_sigma_rad_s: float = 0.1):
        if not (rate_noise_rad_s2 >= 0 and initial_rate_sigma_rad_s > 0):
            raise InvalidInputError("rate_noise_rad_s2 must be >= 0 and initial_rate_sigma_rad_s > 0")
        self.rate_noise = float(rate_noise_rad_s2)
        self.initial_rate_sigma = float(initial_rate_sigma_rad_s)
        self.state: FilterState | None = None

    def _predict(self, time_s: float) -> FilterState:
        s = require(self.state, "the filter's state (set by its first update)")
        dt = time_s - s.time_s
        if not dt >= 0:
            raise InvalidInputError(f"time_s must not go back, got {time_s} after {s.time_s}")
        step = Rotation.from_rotvec(-s.omega_rad_s * dt)
        f = np.eye(6)
        f[:3, :3] = step.as_matrix()
        f[:3, 3:] = -dt * np.eye(3)
        q = np.zeros((6, 6))
        q[3:, 3:] = np.eye(3) * self.rate_noise**2 * dt
        q[:3, :3] = np.eye(3) * self.rate_noise**2 * dt**3 / 3.0
        return FilterState(time_s, step * s.rotation, s.omega_rad_s, f @ s.covariance @ f.T + q)

    def _correct(self, prior: FilterState, residual, h, r) -> FilterState:
        s = h @ prior.covariance @ h.T + r
        gain = prior.covariance @ h.T @ np.linalg.inv(s)
        x = gain @ residual
        cov = (np.eye(6) - gain @ h) @ prior.covariance
        rotation = Rotation.from_rotvec(x[:3]) * prior.rotation
        return FilterState(prior.time_s, rotation, prior.omega_rad_s + x[3:], 0.5 * (cov + cov.T))

    def update_attitude(self, rotation: Rotation, time_s: float, covariance_rad2: ArrayLike) -> FilterState:
        """Take an attitude measurement (``rot_cam_from_icrs``, covariance camera frame, rad^2)."""
        r = _cov3(covariance_rad2, "covariance_rad2")
        if self.state is None:
            cov = np.zeros((6, 6))
            cov[:3, :3] = r
            cov[3:, 3:] = np.eye(3) * self.initial_rate_sigma**2
            self.state = FilterState(float(time_s), rotation, np.zeros(3), cov)
            return self.state
        prior = self._predict(float(time_s))
        residual = (rotation * prior.rotation.inv()).as_rotvec()
        self.state = self._correct(prior, residual, np.hstack([np.eye(3), np.zeros((3, 3))]), r)
        return self.state

    def update_rate(self, omega_rad_s: ArrayLike, time_s: float, covariance_rad2_s2: ArrayLike) -> FilterState:
        """Take a rate measurement (camera frame, rad/s; covariance (rad/s)^2); needs an attitude first."""
        if self.state is None:
            raise InvalidInputError("update_rate needs a first attitude (update_attitude)")
        prior = self._predict(float(time_s))
        residual = np.asarray(omega_rad_s, dtype=float) - prior.omega_rad_s
        h = np.hstack([np.zeros((3, 3)), np.eye(3)])
        self.state = self._correct(prior, residual, h, _cov3(covariance_rad2_s2, "covariance_rad2_s2"))
        return self.state
