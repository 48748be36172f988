"""From a wanted angular acceleration to coil currents, and the torque those currents give.

* One coil (the single-axis plant, normal body +z): only the torque about y can be made,
  ``T_y = n A b_x I`` with b_x the field component across the coil (``|B| cos theta`` in the test
  bed). A field-compensated law divides by b_x; the PD baseline divides by ``|B|``.
* Three coils on body x, y, z: the moment ``m = b x T / |b|^2`` gives the part of the torque T
  normal to the field (the component along b cannot be made by any coil; standard magnetorquer
  allocation, e.g. Markley & Crassidis, *Fundamentals of Spacecraft Attitude Determination and
  Control*, 2014, §7.4); currents ``m / (n A)`` are scaled together when one exceeds the limit, so
  the torque keeps its direction.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ._cubesat import CubeSat
from ._plant import coil_torque_body

MIN_FIELD_FRACTION = 0.05
"""Below this fraction of |B| across the coil the single coil is treated as having no authority."""


def allocate(cubesat: CubeSat, normals_body: NDArray, b_body_t: NDArray, accel_body_rad_s2: NDArray,
             field_compensated: bool = True) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Coil currents (A, one per coil, saturated) for a wanted acceleration, and their torque.

    Parameters
    ----------
    cubesat : CubeSat
    normals_body : ndarray, shape (n, 3)
        Coil normals in the body frame (n = 1: the single-axis coil on +z; n = 3: x, y, z).
    b_body_t : ndarray, shape (3,)
        The field in the body frame as the controller knows it (field model and estimated
        attitude), T.
    accel_body_rad_s2 : ndarray, shape (3,)
        Wanted angular acceleration, body frame.
    field_compensated : bool
        One coil: divide by the field across the coil (True) or by |B| (False).

    Returns
    -------
    currents_a : ndarray, shape (n,)
    torque_body_n_m : ndarray, shape (3,)
        The torque the saturated currents give in ``b_body_t``.
    """
    torque = np.asarray(cubesat.inertia_kg_m2) * np.asarray(accel_body_rad_s2, dtype=float)
    na, limit = cubesat.moment_per_amp, cubesat.max_current_a
    if normals_body.shape[0] == 1:
        n, b = normals_body[0], b_body_t
        across = float(n[2] * b[0] - n[0] * b[2])  # (n x b)_y: torque about y per unit moment
        strength = float(np.linalg.norm(b_body_t))
        divisor = across if field_compensated else math.copysign(strength, across)
        if abs(across) < MIN_FIELD_FRACTION * strength:
            divisor = math.copysign(MIN_FIELD_FRACTION * strength, across or 1.0)
        currents = np.array([min(limit, max(-limit, torque[1] / (na * divisor)))])
    else:
        moment = np.cross(b_body_t, torque) / float(b_body_t @ b_body_t)
        currents = np.linalg.solve(normals_body.T, moment) / na
        peak = float(np.max(np.abs(currents)))
        if peak > limit:
            currents *= limit / peak
    return currents, coil_torque_body(currents, normals_body, na, b_body_t)
