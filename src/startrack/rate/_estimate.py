"""The result of every rate estimator: an angular velocity with its covariance, or a reason.

Convention (as :mod:`startrack.attitude._propagation` and :mod:`startrack.track.predict`):
``omega_rad_s`` is the camera's angular velocity relative to ICRS in camera-frame components,
so that ``rot_cam_from_icrs(t + dt) = exp(-[omega x] dt) rot_cam_from_icrs(t)`` for a constant
rate, and star images move as ``-omega x v`` in the camera frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError, as_float_array, checked_number
from ..results import Status
from ..units import DEG

MIN_EXPOSURE_S = 1e-6
"""The shortest exposure a streak's rate is measured over (s, 1 us): a rate is the streak's length
over the exposure, which overflows beyond it; no camera smears stars into streaks that fast."""

MAX_EXPOSURE_S = 1e6
"""The longest exposure a streak's rate is measured over (s, 11.6 days), for the same reason; no
camera smears stars into streaks that slowly."""


def checked_exposure(exposure_s: object) -> float:
    """``exposure_s`` as a float in [:data:`MIN_EXPOSURE_S`, :data:`MAX_EXPOSURE_S`] s, else an
    InvalidInputError naming it and the range."""
    return checked_number(exposure_s, "exposure_s (seconds)", low=MIN_EXPOSURE_S, high=MAX_EXPOSURE_S)


def checked_prior(prior: ArrayLike | None) -> NDArray[np.float64] | None:
    """A prior rate (3,), rad/s, finite, or None; else an InvalidInputError naming ``prior_omega_rad_s``."""
    if prior is None:
        return None
    w = as_float_array(prior, "prior_omega_rad_s")
    if w.shape != (3,) or not np.all(np.isfinite(w)):
        raise InvalidInputError(f"prior_omega_rad_s must be 3 finite numbers (rad/s), got {prior!r}")
    return w


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
