"""The plant: a rigid cube turned by magnetic torque coils, integrated with scipy.

* :class:`SingleAxisPlant` (Sease 2013 ch. 5, eq. 5.2-5.6): rotation by theta about y, one coil
  with its normal on body +z, the test bed's field along reference +x, so
  ``J22 theta'' = n A |B| I (1 - 2 q2^2)`` with ``q2 = sin(theta / 2)``.
* :class:`ThreeAxisPlant`: Euler's equations ``J w' = T - w x J w`` with three coils on body
  x, y, z, ``T = sum_i n A I_i (e_i x b_body)``, quaternion kinematics, in any
  :class:`.field.FieldModel` (the Helmholtz field, or the dipole along an orbit).

Both hold the state at time ``t_s`` and advance it over one control period with the coil currents
held constant (zero-order hold, as the seed's PWM does), by ``scipy.integrate.odeint`` (LSODA,
rtol 1e-10; it agrees with ``solve_ivp``'s RK45 to 1e-13 rad over a period at an eighth of its
call overhead, which matters at 40 Hz over 700 s); :meth:`step` can also return the state at
times inside the period (a camera's mid-exposure). Attitudes are ``rot_ref_from_body`` (body vectors to the reference
frame), rates are body-frame, rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import odeint
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ._cubesat import CubeSat
from ._field import FieldModel, UniformField

RTOL = 1e-10
ATOL = 1e-12
E_Y = np.array([0.0, 1.0, 0.0])


class Plant(Protocol):
    """What the closed loop needs from a plant."""

    cubesat: CubeSat
    coil_normals_body: NDArray[np.float64]
    t_s: float

    @property
    def field(self) -> FieldModel: ...

    def rot_ref_from_body(self) -> Rotation: ...

    def rate_body(self) -> NDArray[np.float64]: ...

    def step(self, currents_a: ArrayLike, dt_s: float, t_eval: Sequence[float] = ()
             ) -> list[tuple[Rotation, NDArray[np.float64]]]: ...


def coil_torque_body(currents_a: ArrayLike, normals_body: NDArray, moment_per_amp: float,
                     b_body_t: NDArray) -> NDArray[np.float64]:
    """Torque of coils (normals (n, 3), currents (n,)) in the body-frame field ``b_body_t``, N m."""
    mx, my, mz = (moment_per_amp * np.asarray(currents_a, dtype=float) @ normals_body).tolist()
    bx, by, bz = (float(b) for b in b_body_t)
    return np.array([my * bz - mz * by, mz * bx - mx * bz, mx * by - my * bx])  # m x b (np.cross is slow on 3-vectors)


def y_rotation(theta_rad: float) -> Rotation:
    """``rot_ref_from_body`` of a turn by ``theta_rad`` about y."""
    return Rotation.from_rotvec(theta_rad * E_Y)


def _time_grid(t0: float, t1: float, t_eval: Sequence[float]) -> tuple[list[float], list[int]]:
    """odeint's strictly increasing times from t0 to t1 through the requested ones, and where each
    requested time sits in it (in the order given)."""
    snap = 1e-9 * max(1.0, abs(t1))  # times this close to an end are that end
    wanted = [t0 if abs(t - t0) <= snap else t1 if abs(t - t1) <= snap else float(t) for t in t_eval]
    if any(not t0 <= t <= t1 for t in wanted):
        raise InvalidInputError(f"t_eval must lie within the step [{t0}, {t1}] s, got {list(t_eval)!r}")
    grid = [t0, *sorted({t for t in wanted if t0 < t < t1}), t1]
    return grid, [grid.index(t) for t in wanted]


def _checked_step(currents_a: ArrayLike, n_coils: int, dt_s: float) -> NDArray[np.float64]:
    currents = np.atleast_1d(np.asarray(currents_a, dtype=float))
    if currents.shape != (n_coils,) or not np.all(np.isfinite(currents)):
        raise InvalidInputError(f"currents_a must be {n_coils} finite currents (A), got {currents_a!r}")
    if not (math.isfinite(dt_s) and dt_s > 0):
        raise InvalidInputError(f"dt_s must be a positive duration (s), got {dt_s!r}")
    return currents


def _rotate_inverse(q: Sequence[float], v: Sequence[float] | NDArray[np.float64]) -> tuple[float, float, float]:
    """``Rotation.from_quat(q).inv().apply(v)`` for one unit quaternion (scalar last), in floats."""
    ux, uy, uz, w = -q[0], -q[1], -q[2], q[3]
    vx, vy, vz = v
    tx, ty, tz = 2.0 * (uy * vz - uz * vy), 2.0 * (uz * vx - ux * vz), 2.0 * (ux * vy - uy * vx)
    return (vx + w * tx + uy * tz - uz * ty, vy + w * ty + uz * tx - ux * tz, vz + w * tz + ux * ty - uy * tx)


class SingleAxisPlant:
    """Rotation about y with one coil (Sease 2013 eq. 5.6); state theta (rad) and omega (rad/s).

    Parameters
    ----------
    cubesat : CubeSat
    theta0_rad, omega0_rad_s : float
        Initial angle and rate about y.
    t0_s : float
        Initial time, s.
    """

    coil_normals_body = np.array([[0.0, 0.0, 1.0]])

    def __init__(self, cubesat: CubeSat, theta0_rad: float = 0.0, omega0_rad_s: float = 0.0, t0_s: float = 0.0):
        self.cubesat = cubesat
        self.field = UniformField((cubesat.field_t, 0.0, 0.0))
        self.theta_rad, self.omega_rad_s, self.t_s = float(theta0_rad), float(omega0_rad_s), float(t0_s)

    def accel_rad_s2(self, theta_rad: float, current_a: float) -> float:
        """``n A |B| I (1 - 2 q2^2) / J22`` with ``q2 = sin(theta / 2)``, rad/s^2."""
        q2 = math.sin(0.5 * theta_rad)
        sat = self.cubesat
        return sat.moment_per_amp * sat.field_t * current_a * (1.0 - 2.0 * q2 * q2) / sat.j22

    def rot_ref_from_body(self) -> Rotation:
        return y_rotation(self.theta_rad)

    def rate_body(self) -> NDArray[np.float64]:
        return self.omega_rad_s * E_Y

    def step(self, currents_a: ArrayLike, dt_s: float, t_eval: Sequence[float] = ()
             ) -> list[tuple[Rotation, NDArray[np.float64]]]:
        """Advance by ``dt_s`` with the coil current held; states at ``t_eval`` (inside the step)."""
        current = float(_checked_step(currents_a, 1, dt_s)[0])
        grid, where = _time_grid(self.t_s, self.t_s + dt_s, t_eval)
        ys = odeint(lambda y, _t: (y[1], self.accel_rad_s2(y[0], current)), (self.theta_rad, self.omega_rad_s),
                    grid, rtol=RTOL, atol=ATOL)
        self.theta_rad, self.omega_rad_s, self.t_s = float(ys[-1, 0]), float(ys[-1, 1]), grid[-1]
        return [(y_rotation(ys[k, 0]), ys[k, 1] * E_Y) for k in where]


class ThreeAxisPlant:
    """A free rigid body with three coils on body x, y, z in a field model.

    Parameters
    ----------
    cubesat : CubeSat
    field : FieldModel
    rot0_ref_from_body : Rotation
    omega0_body_rad_s : array_like, shape (3,)
    t0_s : float
    """

    coil_normals_body = np.eye(3)

    def __init__(self, cubesat: CubeSat, field: FieldModel, rot0_ref_from_body: Rotation | None = None,
                 omega0_body_rad_s: ArrayLike = (0.0, 0.0, 0.0), t0_s: float = 0.0):
        self.cubesat, self.field = cubesat, field
        rot = Rotation.identity() if rot0_ref_from_body is None else rot0_ref_from_body
        self._state = np.concatenate([rot.as_quat(), np.asarray(omega0_body_rad_s, dtype=float)])
        if self._state.shape != (7,) or not np.all(np.isfinite(self._state)):
            raise InvalidInputError(f"omega0_body_rad_s must be 3 finite rates (rad/s), got {omega0_body_rad_s!r}")
        self.t_s = float(t0_s)
        self._inertia = cubesat.inertia_matrix
        self._inertia_inv = np.linalg.inv(self._inertia)

    def rot_ref_from_body(self) -> Rotation:
        return Rotation.from_quat(self._state[:4])

    def rate_body(self) -> NDArray[np.float64]:
        return self._state[4:].copy()

    def _derivative(self, y: NDArray, t: float, moment: tuple[float, float, float]) -> list[float]:
        """d/dt of (quaternion, rate), in plain floats (numpy's calls on small arrays cost more than the arithmetic)."""
        x, yq, z, w = y[:4] / math.sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2] + y[3] * y[3])
        p, q, r = y[4], y[5], y[6]
        bx, by, bz = _rotate_inverse((x, yq, z, w), self.field.field_ref(t))
        mx, my, mz = moment
        j1, j2, j3 = self.cubesat.inertia_kg_m2
        tx, ty, tz = my * bz - mz * by, mz * bx - mx * bz, mx * by - my * bx
        return [0.5 * (w * p + yq * r - z * q), 0.5 * (w * q + z * p - x * r), 0.5 * (w * r + x * q - yq * p),
                -0.5 * (x * p + yq * q + z * r),
                (tx - (j3 - j2) * q * r) / j1, (ty - (j1 - j3) * r * p) / j2, (tz - (j2 - j1) * p * q) / j3]

    def step(self, currents_a: ArrayLike, dt_s: float, t_eval: Sequence[float] = ()
             ) -> list[tuple[Rotation, NDArray[np.float64]]]:
        """Advance by ``dt_s`` with the coil currents held; states at ``t_eval`` (inside the step)."""
        currents = _checked_step(currents_a, 3, dt_s)
        grid, where = _time_grid(self.t_s, self.t_s + dt_s, t_eval)
        moment = tuple((self.cubesat.moment_per_amp * currents @ self.coil_normals_body).tolist())
        ys = odeint(self._derivative, self._state, grid, args=(moment,), rtol=RTOL, atol=ATOL)
        end = ys[-1]
        self._state = np.concatenate([end[:4] / np.linalg.norm(end[:4]), end[4:]])
        self.t_s = grid[-1]
        return [(Rotation.from_quat(ys[k, :4]), ys[k, 4:].copy()) for k in where]
