"""Path tracking: the error quaternion, input-output linearisation, LQR and the PD baseline
(Sease 2013 ch. 5, eq. 5.16-5.32; Sease 2013 Chapter 5).

Error. For a planned attitude p and an attitude q, both turns about y, the error quaternion
(eq. 5.17) is ``q_E2 = -p4 q2 + q4 p2``, ``q_E4 = p4 q4 + q2 p2`` and the seed's error is
``e = 2 q_E2 q_E4`` (eq. 5.20). With ``q2 = sin(theta / 2)``, ``p2 = sin(phi / 2)`` this is exactly
``e = sin(phi - theta)``, so

    e'  = cos(phi - theta) (phi' - w)
    e'' = -sin(phi - theta) (phi' - w)^2 + cos(phi - theta) (phi'' - w')

Input-output linearisation: asking ``e'' = v`` gives the angular acceleration

    w' = phi'' - (v + sin(phi - theta) (phi' - w)^2) / cos(phi - theta)

(the seed's eq. 5.26-5.27 in angle form; the coil current then follows from
``w' = n A b_x I / J22``, :mod:`._actuation`). The linear system ``x = (e', e)``, ``x' = A x + B v``
with ``A = [[0, 0], [1, 0]]``, ``B = [1, 0]^T`` (eq. 5.28-5.29) is regulated by ``v = -K x``,
``K = R^-1 B^T P`` with P from the continuous algebraic Riccati equation (eq. 5.31-5.32, scipy's
``solve_continuous_are``), Q = 20 I and R = 1 as in the seed.

The PD baseline asks ``w' = kp (phi - theta) + kd (phi' - w)`` with the same two gains, without
the plan's acceleration, the error's curvature terms or the field compensation (its current is
computed with the full field, not its component across the coil).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import solve_continuous_are

from ..errors import InvalidInputError

A_DOUBLE_INTEGRATOR = np.array([[0.0, 0.0], [1.0, 0.0]])
B_DOUBLE_INTEGRATOR = np.array([[1.0], [0.0]])


@dataclass(frozen=True)
class LQRGain:
    """The regulator of the linearised error: ``v = -(k_rate e' + k_angle e)``.

    Attributes
    ----------
    gain : ndarray, shape (1, 2)
        K, acting on (e', e): units 1/s and 1/s^2.
    riccati : ndarray, shape (2, 2)
        P, the stabilising solution of the Riccati equation.
    """

    gain: NDArray[np.float64]
    riccati: NDArray[np.float64]

    @property
    def k_rate(self) -> float:
        return float(self.gain[0, 0])

    @property
    def k_angle(self) -> float:
        return float(self.gain[0, 1])


def lqr_gain(q_weight: float = 20.0, r_weight: float = 1.0) -> LQRGain:
    """LQR of the double integrator with ``Q = q_weight I`` and ``R = r_weight`` (seed: 20 and 1)."""
    for name, value in (("q_weight", q_weight), ("r_weight", r_weight)):
        if not (math.isfinite(value) and value > 0):
            raise InvalidInputError(f"{name} must be a positive weight, got {value!r}")
    q, r = q_weight * np.eye(2), np.array([[r_weight]])
    p = solve_continuous_are(A_DOUBLE_INTEGRATOR, B_DOUBLE_INTEGRATOR, q, r)
    return LQRGain(gain=np.linalg.solve(r, B_DOUBLE_INTEGRATOR.T @ p), riccati=p)


def error_quaternion(q2: float, q4: float, p2: float, p4: float) -> tuple[float, float]:
    """(q_E2, q_E4) of attitude (q2, q4) against the planned (p2, p4), eq. 5.17."""
    return -p4 * q2 + q4 * p2, p4 * q4 + q2 * p2


def tracking_error(theta_rad: float, omega_rad_s: float, phi: float, phi_dot: float) -> tuple[float, float]:
    """(e, e') with ``e = 2 q_E2 q_E4`` (eq. 5.20) for angle theta against the plan phi."""
    qe2, qe4 = error_quaternion(math.sin(0.5 * theta_rad), math.cos(0.5 * theta_rad),
                                math.sin(0.5 * phi), math.cos(0.5 * phi))
    return 2.0 * qe2 * qe4, math.cos(phi - theta_rad) * (phi_dot - omega_rad_s)


@dataclass(frozen=True)
class LQRTracking:
    """The seed's tracking law: input-output linearisation + LQR; ``accel`` gives w' (rad/s^2)."""

    lqr: LQRGain
    name: str = "lqr"
    field_compensated: bool = True

    @property
    def k_angle(self) -> float:
        return self.lqr.k_angle

    @property
    def k_rate(self) -> float:
        return self.lqr.k_rate

    def accel(self, theta_rad: float, omega_rad_s: float, plan: tuple[float, float, float]) -> float:
        phi, phi_dot, phi_ddot = plan
        e, e_dot = tracking_error(theta_rad, omega_rad_s, phi, phi_dot)
        v = -(self.lqr.k_rate * e_dot + self.lqr.k_angle * e)
        delta = phi - theta_rad
        cos_delta = max(math.cos(delta), 0.1)  # beyond ~84 deg of error the linearisation is meaningless
        return phi_ddot - (v + math.sin(delta) * (phi_dot - omega_rad_s) ** 2) / cos_delta


@dataclass(frozen=True)
class PDTracking:
    """The baseline: ``w' = kp (phi - theta) + kd (phi' - w)``, no feed-forward or linearisation."""

    k_angle: float
    k_rate: float
    name: str = "pd"
    field_compensated: bool = False

    def accel(self, theta_rad: float, omega_rad_s: float, plan: tuple[float, float, float]) -> float:
        phi, phi_dot, _ = plan
        return self.k_angle * (phi - theta_rad) + self.k_rate * (phi_dot - omega_rad_s)

    @classmethod
    def from_lqr(cls, lqr: LQRGain) -> PDTracking:
        """The PD law with the LQR's two gains."""
        return cls(k_angle=lqr.k_angle, k_rate=lqr.k_rate)


def tracking_law(name: str, q_weight: float = 20.0, r_weight: float = 1.0) -> LQRTracking | PDTracking:
    """The law called ``name`` ("lqr" or "pd") with gains from Q = q_weight I, R = r_weight."""
    lqr = lqr_gain(q_weight, r_weight)
    if name == "lqr":
        return LQRTracking(lqr)
    if name == "pd":
        return PDTracking.from_lqr(lqr)
    raise InvalidInputError(f"law must be 'lqr' or 'pd', got {name!r}")
