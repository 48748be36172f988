"""Attitude during an exposure and over a sequence: quaternion kinematics and attitude profiles.

Kinematics (Sease 2013 §"Streaking Dynamics", eq. 2.12, with the
sign fixed there): the camera turns at angular velocity omega, expressed in the **camera frame**
(rad/s). The attitude ``A = rot_cam_from_icrs`` then obeys ``dA/dt = -[omega x] A``: a star fixed
in ICRS moves in the camera frame as ``dv/dt = -omega x v``. As quaternions (scalar last, the
order of ``Rotation.as_quat``), ``dq/dt = 1/2 (-omega, 0) (x) q`` with (x) the Hamilton product
that composes rotations. For a constant omega the solution is exact,
``A(t) = exp(-[omega x] (t - t_ref)) A(t_ref)``; a time-varying omega is integrated with the
classical fourth-order Runge-Kutta scheme on the quaternion, in steps of at most
:data:`RK4_MAX_ANGLE_RAD` of rotation.

Profiles (all give ``attitudes(times_s) -> Rotation`` and ``rates(times_s) -> (N, 3)`` rad/s in
the camera frame, times in seconds from the profile's origin):

- :class:`ConstantRate`: inertial hold (omega = 0), a constant-rate slew, or a tumble about any
  axis fixed in the camera (``tumble``);
- :class:`VaryingRate`: omega(t) from any function (e.g. constant angular acceleration);
- :class:`Slew`: hold, rotate at constant rate from one attitude to another, hold;
- :class:`RecordedProfile`: attitudes recorded at given times (a file:
  :func:`startrack.simulate._profile_file.load_profile`),
  interpolated by spherical linear interpolation, i.e. constant rate between samples.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation, Slerp

from ..errors import InvalidInputError
from . import _checks

RK4_MAX_ANGLE_RAD = 1e-3
"""Largest rotation per Runge-Kutta step of :class:`VaryingRate` (error ~ 1e-15 rad per step)."""


class AttitudeProfile(Protocol):
    """Anything that gives ``rot_cam_from_icrs`` and the camera-frame rate at given times (s)."""

    def attitudes(self, times_s: ArrayLike) -> Rotation: ...

    def rates(self, times_s: ArrayLike) -> NDArray[np.float64]: ...


def _times(times_s: ArrayLike) -> NDArray[np.float64]:
    t = np.atleast_1d(np.asarray(times_s, dtype=float))
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise InvalidInputError("times_s must be a finite number or 1-D array of seconds")
    return t


def _single(rot: Rotation, name: str) -> Rotation:
    if not isinstance(rot, Rotation) or not rot.single:
        raise InvalidInputError(f"{name} must be a single scipy Rotation (not a stack)")
    return rot


def hamilton(p: NDArray, q: NDArray) -> NDArray[np.float64]:
    """Hamilton products of scalar-last quaternions (..., 4): the quaternion of ``P * Q``."""
    pv, pw = p[..., :3], p[..., 3:]
    qv, qw = q[..., :3], q[..., 3:]
    vec = pw * qv + qw * pv + np.cross(pv, qv)
    return np.concatenate([vec, pw * qw - np.sum(pv * qv, axis=-1, keepdims=True)], axis=-1)


def quaternion_rate(q: NDArray, omega_cam: NDArray) -> NDArray[np.float64]:
    """dq/dt of ``rot_cam_from_icrs`` quaternions (..., 4) turning at ``omega_cam`` (..., 3)."""
    pure = np.concatenate([-np.asarray(omega_cam, dtype=float), np.zeros(q.shape[:-1] + (1,))], axis=-1)
    return 0.5 * hamilton(pure, q)


@dataclass(frozen=True)
class ConstantRate:
    """A constant camera-frame rate: ``A(t) = exp(-[omega x] (t - t_ref_s)) A_ref``.

    Parameters
    ----------
    rot_ref : Rotation
        ``rot_cam_from_icrs`` at ``t_ref_s``.
    rate_rad_s : array_like, shape (3,)
        Angular velocity of the camera in the camera frame, rad/s (zero: inertial hold).
    t_ref_s : float
    """

    rot_ref: Rotation
    rate_rad_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    t_ref_s: float = 0.0

    def __post_init__(self) -> None:
        _single(self.rot_ref, "rot_ref")
        rate = _checks.finite_array("rate_rad_s", self.rate_rad_s, (3,)).copy()
        rate.flags.writeable = False
        object.__setattr__(self, "rate_rad_s", rate)
        object.__setattr__(self, "t_ref_s", float(self.t_ref_s))

    @property
    def static(self) -> bool:
        return not np.any(self.rate_rad_s)

    def attitudes(self, times_s: ArrayLike) -> Rotation:
        dt = _times(times_s) - self.t_ref_s
        return Rotation.from_rotvec(-dt[:, None] * self.rate_rad_s[None, :]) * self.rot_ref

    def rates(self, times_s: ArrayLike) -> NDArray[np.float64]:
        return np.broadcast_to(self.rate_rad_s, (_times(times_s).size, 3)).copy()


def inertial_hold(rot_cam_from_icrs: Rotation) -> ConstantRate:
    """The attitude held fixed in ICRS."""
    return ConstantRate(rot_cam_from_icrs)


def tumble(rot_ref: Rotation, axis_cam: ArrayLike, rate_rad_s: float, t_ref_s: float = 0.0) -> ConstantRate:
    """Rotation at ``rate_rad_s`` about ``axis_cam`` (any direction in the camera frame)."""
    axis = _checks.finite_array("axis_cam", axis_cam, (3,))
    norm = float(np.linalg.norm(axis))
    if norm == 0.0:
        raise InvalidInputError("axis_cam must not be the zero vector")
    return ConstantRate(rot_ref, axis / norm * float(rate_rad_s), t_ref_s)


@dataclass(frozen=True, eq=False)
class VaryingRate:
    """A camera-frame rate that changes with time, integrated from ``rot_ref`` at ``t_ref_s``.

    Parameters
    ----------
    rot_ref : Rotation
    rate_fn : callable
        ``rate_fn(times_s (N,)) -> (N, 3)`` angular velocity in the camera frame, rad/s.
    t_ref_s : float
    """

    rot_ref: Rotation
    rate_fn: Callable[[NDArray[np.float64]], NDArray[np.float64]]
    t_ref_s: float = 0.0

    def __post_init__(self) -> None:
        _single(self.rot_ref, "rot_ref")

    @classmethod
    def accelerating(cls, rot_ref: Rotation, rate_rad_s: ArrayLike, accel_rad_s2: ArrayLike,
                     t_ref_s: float = 0.0) -> VaryingRate:
        """omega(t) = rate + accel (t - t_ref): a constant angular acceleration (camera frame)."""
        w0 = _checks.finite_array("rate_rad_s", rate_rad_s, (3,)).copy()
        alpha = _checks.finite_array("accel_rad_s2", accel_rad_s2, (3,)).copy()
        t_ref = float(t_ref_s)
        return cls(rot_ref, lambda t: w0[None, :] + alpha[None, :] * (np.asarray(t)[:, None] - t_ref), t_ref)

    def rates(self, times_s: ArrayLike) -> NDArray[np.float64]:
        t = _times(times_s)
        rates = np.asarray(self.rate_fn(t), dtype=float)
        if rates.shape != (t.size, 3) or not np.all(np.isfinite(rates)):
            raise InvalidInputError(f"rate_fn must return finite rates of shape ({t.size}, 3)")
        return rates

    def attitudes(self, times_s: ArrayLike) -> Rotation:
        t = _times(times_s)
        quats = np.empty((t.size, 4))
        q_ref = self.rot_ref.as_quat()
        for sign in (1.0, -1.0):  # forwards from t_ref through later times, backwards through earlier
            mask = (t - self.t_ref_s) * sign >= 0
            order = np.flatnonzero(mask)[np.argsort(sign * t[mask], kind="stable")]
            quats[order] = self._integrate(q_ref, t[order])
        return Rotation.from_quat(quats)

    def _integrate(self, q: NDArray, targets: NDArray) -> NDArray:
        out = np.empty((targets.size, 4))
        now = self.t_ref_s
        for i, target in enumerate(targets):
            q = self._advance(q, now, float(target))
            now = float(target)
            out[i] = q
        return out

    def _advance(self, q: NDArray, t0: float, t1: float) -> NDArray:
        if t1 == t0:
            return q
        rate = float(np.max(np.linalg.norm(self.rates(np.linspace(t0, t1, 5)), axis=1)))
        steps = max(1, math.ceil(rate * abs(t1 - t0) / RK4_MAX_ANGLE_RAD))
        grid = np.linspace(t0, t1, steps + 1)
        h = (t1 - t0) / steps
        mids = self.rates(grid[:-1] + h / 2)
        ends = self.rates(grid)
        for k in range(steps):
            q = _rk4_step(q, h, ends[k], mids[k], ends[k + 1])
        return q / np.linalg.norm(q)


def _rk4_step(q: NDArray, h: float, w0: NDArray, wm: NDArray, w1: NDArray) -> NDArray:
    k1 = quaternion_rate(q, w0)
    k2 = quaternion_rate(q + 0.5 * h * k1, wm)
    k3 = quaternion_rate(q + 0.5 * h * k2, wm)
    k4 = quaternion_rate(q + h * k3, w1)
    return q + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def relative_rate(rot_a: Rotation, rot_b: Rotation, dt_s: float | NDArray) -> NDArray[np.float64]:
    """The constant camera-frame rate (rad/s) that turns ``rot_a`` into ``rot_b`` in ``dt_s``."""
    return -(rot_b * rot_a.inv()).as_rotvec() / np.asarray(dt_s, dtype=float)[..., None]


@dataclass(frozen=True)
class Slew:
    """Hold ``rot_from``, turn at constant rate to ``rot_to`` over ``duration_s`` from
    ``t_start_s`` (along the shortest rotation), then hold ``rot_to``."""

    rot_from: Rotation
    rot_to: Rotation
    t_start_s: float
    duration_s: float

    def __post_init__(self) -> None:
        _single(self.rot_from, "rot_from")
        _single(self.rot_to, "rot_to")
        object.__setattr__(self, "duration_s", _checks.positive("duration_s", self.duration_s))

    @property
    def rate_rad_s(self) -> NDArray[np.float64]:
        return relative_rate(self.rot_from, self.rot_to, self.duration_s)

    def attitudes(self, times_s: ArrayLike) -> Rotation:
        s = np.clip((_times(times_s) - self.t_start_s) / self.duration_s, 0.0, 1.0)
        return Rotation.from_rotvec(-s[:, None] * self.duration_s * self.rate_rad_s) * self.rot_from

    def rates(self, times_s: ArrayLike) -> NDArray[np.float64]:
        t = _times(times_s)
        moving = (t >= self.t_start_s) & (t < self.t_start_s + self.duration_s)
        return moving[:, None] * self.rate_rad_s[None, :]


@dataclass(frozen=True, eq=False)
class RecordedProfile:
    """Attitudes at increasing times, interpolated at constant rate between samples.

    Outside the recorded span the first / last attitude is held (rate 0).
    """

    times_s: NDArray[np.float64]
    rotations: Rotation
    _slerp: Slerp = field(init=False, repr=False)

    def __post_init__(self) -> None:
        t = _times(self.times_s)
        if t.size < 2 or np.any(np.diff(t) <= 0):
            raise InvalidInputError("a recorded profile needs at least 2 strictly increasing times")
        if not isinstance(self.rotations, Rotation) or self.rotations.single or len(self.rotations) != t.size:
            raise InvalidInputError(f"rotations must be a stack of {t.size} Rotations, one per time")
        object.__setattr__(self, "times_s", t)
        object.__setattr__(self, "_slerp", Slerp(t, self.rotations))

    def attitudes(self, times_s: ArrayLike) -> Rotation:
        return self._slerp(np.clip(_times(times_s), self.times_s[0], self.times_s[-1]))

    def rates(self, times_s: ArrayLike) -> NDArray[np.float64]:
        t = _times(times_s)
        seg = np.clip(np.searchsorted(self.times_s, t, side="right") - 1, 0, self.times_s.size - 2)
        rates = relative_rate(self.rotations[seg], self.rotations[seg + 1],
                              self.times_s[seg + 1] - self.times_s[seg])
        inside = (t >= self.times_s[0]) & (t < self.times_s[-1])
        return rates * inside[:, None]
