"""The result of every rate estimator: an angular velocity with its covariance, or a reason.

Convention (as :mod:`startrack.attitude._propagation` and :mod:`startrack.track.predict`):
``omega_rad_s`` is the camera's angular velocity relative to ICRS in camera-frame components,
so that ``rot_cam_from_icrs(t + dt) = exp(-[omega x] dt) rot_cam_from_icrs(t)`` for a constant
rate, and star images move as ``-omega x v`` in the camera frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..results import Status
from ..units import DEG


def _nan3() -> NDArray[np.float64]:
    return np.full(3, np.nan)


@dataclass(frozen=True)
class RateEstimate:
    """An angular-velocity estimate.

    Attributes
    ----------
    status : Status
        ``Status.OK``, or why there is no estimate (TOO_FEW_STARS, DEGENERATE, NO_MATCH).
    reason : str
        Words for a status that is not OK; empty otherwise.
    omega_rad_s : ndarray, shape (3,)
        Angular velocity, camera frame, rad/s (NaN when not OK).
    covariance_rad2_s2 : ndarray, shape (3, 3) or None
        Its covariance, (rad/s)^2, when the inputs' uncertainties were given.
    method : str
        Which estimator produced it.
    used : ndarray of bool or None
        For estimators that reject outliers: which input pairs were kept.
    """

    status: Status
    reason: str = ""
    omega_rad_s: NDArray[np.float64] = None  # type: ignore[assignment]
    covariance_rad2_s2: NDArray[np.float64] | None = None
    method: str = ""
    used: NDArray[np.bool_] | None = None

    def __post_init__(self) -> None:
        if self.omega_rad_s is None:
            object.__setattr__(self, "omega_rad_s", _nan3())

    @property
    def ok(self) -> bool:
        return self.status is Status.OK

    @property
    def rate_deg_s(self) -> float:
        """Magnitude of the rate, degrees per second."""
        return float(np.linalg.norm(self.omega_rad_s) / DEG)

    @property
    def axis(self) -> NDArray[np.float64]:
        """Unit rotation axis in the camera frame (NaN for a zero or missing rate)."""
        norm = np.linalg.norm(self.omega_rad_s)
        return self.omega_rad_s / norm if norm > 0 else _nan3()

    @property
    def sigma_rad_s(self) -> NDArray[np.float64]:
        """1-sigma of each component, rad/s (NaN without a covariance)."""
        if self.covariance_rad2_s2 is None:
            return _nan3()
        return np.sqrt(np.diag(self.covariance_rad2_s2))


def failed(status: Status, reason: str, method: str) -> RateEstimate:
    """A RateEstimate with no rate."""
    return RateEstimate(status=status, reason=reason, method=method)


def axis_error_rad(omega_a, omega_b) -> float:
    """Angle between two rate axes (radians, stable atan2 form)."""
    a, b = np.asarray(omega_a, dtype=float), np.asarray(omega_b, dtype=float)
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b)))
