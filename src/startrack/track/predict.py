"""Attitude prediction from an angular rate, and the rate from two attitudes (seed 004 §2.2).

The rate ``w`` is the camera's angular velocity in the camera frame (rad/s). Inertial directions
then turn by ``-w dt`` in the camera frame, so the attitude a time ``dt`` later is
``exp(-[w x] dt) C``, whose first-order form is seed 004's eq. 1, ``C_p = (I - [w x] dt) C``.
The exponential map is used here (no re-orthonormalisation needed). The inverse, eq. 3,
``[w x] ~ (I - C(t + dt) C(t)^T) / dt``, is taken exactly with the logarithm map.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError


def propagate_attitude(rot_cam_from_icrs: Rotation, rate_rad_s: ArrayLike, dt_s: float) -> Rotation:
    """The attitude ``dt_s`` later for a constant camera-frame rate (rad/s)."""
    rate = np.asarray(rate_rad_s, dtype=float)
    if rate.shape != (3,) or not np.all(np.isfinite(rate)):
        raise InvalidInputError(f"rate_rad_s must be 3 finite numbers, got {rate_rad_s!r}")
    return Rotation.from_rotvec(-rate * float(dt_s)) * rot_cam_from_icrs


def rate_from_attitudes(rot_before: Rotation, rot_after: Rotation, dt_s: float) -> NDArray[np.float64]:
    """Mean camera-frame angular rate (rad/s) that turns ``rot_before`` into ``rot_after``."""
    if not dt_s > 0:
        raise InvalidInputError(f"dt_s must be positive, got {dt_s!r}")
    return -(rot_after * rot_before.inv()).as_rotvec() / dt_s
