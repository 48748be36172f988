"""Measurements, state estimates and their propagation between measurements.

A :class:`Measurement` is what a sensor reports: an attitude valid at ``t_attitude_s``, a body
rate valid at ``t_rate_s`` (earlier than the attitude when the rate is a smoothed difference of
attitudes), both available to the controller from ``t_available_s``. The controller propagates
the newest available one to the present with the angular accelerations it commanded itself
(:class:`CommandLog`, zero-order hold per control period):

    w(t)     = w_m + V(t) - V(t_rate)
    theta(t) = theta_m + (w_m - V(t_rate)) (t - t_att) + P(t) - P(t_att)

with ``V = int a dt`` and ``P = int V dt`` per body axis, applied as a small body-frame rotation
``rot(t) = rot_m * exp(dphi)`` (the rotations over one latency, < 0.1 rad, commute to second
order). Truth and IMU measurements arrive at every control tick, so the propagation is nil.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class Measurement:
    """One sensor report: ``rot_ref_from_body`` and the body rate (rad/s), with their times (s)."""

    t_attitude_s: float
    t_rate_s: float
    t_available_s: float
    rot_ref_from_body: Rotation
    rate_body_rad_s: NDArray[np.float64]


@dataclass(frozen=True)
class Estimate:
    """The controller's state at ``t_s``; ``valid`` is False before the first measurement."""

    t_s: float
    rot_ref_from_body: Rotation
    rate_body_rad_s: NDArray[np.float64]
    valid: bool
    age_s: float = 0.0

    @property
    def theta_rad(self) -> float:
        """Angle of the turn about y (exact for a pure y turn; the boresight's azimuth otherwise)."""
        return y_angle(self.rot_ref_from_body)

    @property
    def omega_rad_s(self) -> float:
        return float(self.rate_body_rad_s[1])


def y_angle(rot_ref_from_body: Rotation) -> float:
    """``atan2(R[0, 2], R[2, 2])``: theta of ``R = R_y(theta)``, from the quaternion."""
    x, y, z, w = rot_ref_from_body.as_quat().tolist()
    return math.atan2(2.0 * (x * z + y * w), 1.0 - 2.0 * (x * x + y * y))


class CommandLog:
    """Angular accelerations the controller commanded, held from each tick to the next."""

    def __init__(self) -> None:
        self._t: list[float] = []
        self._a: list[NDArray] = []
        self._v: list[NDArray] = []
        self._p: list[NDArray] = []

    def append(self, t_s: float, accel_body_rad_s2: NDArray) -> None:
        """The acceleration commanded from ``t_s`` on (times must increase)."""
        a = np.asarray(accel_body_rad_s2, dtype=float)
        if self._t:
            v, p = self._integrals(t_s)
        else:
            v, p = np.zeros(3), np.zeros(3)
        self._t.append(float(t_s))
        self._a.append(a)
        self._v.append(v)
        self._p.append(p)

    def _integrals(self, t_s: float) -> tuple[NDArray, NDArray]:
        """V(t) and P(t); before the first command they are 0, after the last it continues."""
        k = bisect.bisect_right(self._t, t_s) - 1
        if k < 0:
            return np.zeros(3), np.zeros(3)
        dt = t_s - self._t[k]
        a, v = self._a[k], self._v[k]
        return v + a * dt, self._p[k] + v * dt + 0.5 * a * dt * dt

    def propagate(self, m: Measurement, t_s: float) -> tuple[Rotation, NDArray[np.float64]]:
        """The measurement carried to ``t_s``: (rot_ref_from_body, body rate)."""
        v_rate, _ = self._integrals(m.t_rate_s)
        v_att, p_att = self._integrals(m.t_attitude_s)
        v_now, p_now = self._integrals(t_s)
        rate0 = m.rate_body_rad_s - v_rate
        dphi = rate0 * (t_s - m.t_attitude_s) + p_now - p_att
        return m.rot_ref_from_body * Rotation.from_rotvec(dphi), rate0 + v_now


def estimate_from(log: CommandLog, m: Measurement | None, t_s: float) -> Estimate:
    """The estimate at ``t_s`` from measurement ``m`` (None: invalid, at rest, y angle 0)."""
    if m is None:
        return Estimate(t_s, Rotation.identity(), np.zeros(3), False, math.inf)
    if t_s == m.t_attitude_s == m.t_rate_s:
        return Estimate(t_s, m.rot_ref_from_body, m.rate_body_rad_s, True, 0.0)
    rot, rate = log.propagate(m, t_s)
    return Estimate(t_s, rot, rate, True, t_s - m.t_attitude_s)
