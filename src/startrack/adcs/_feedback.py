"""Feedback sources: the truth, and an IMU with the seed's noise bounds.

Every source answers ``estimate(t_s, plant, log)`` at each control tick; sources that sample the
true state during a plant step (cameras, :mod:`._star_tracker_feedback`) list those instants with
``sample_times`` and receive the states through ``observe``.

IMU (Sease 2013 ch. 5 "Simulation Results", the VN-100 data sheet bounds): every tick, with no
latency, ``q = q_true + dq`` on each vector component of the quaternion (scalar recomputed) and
``w = w_true + dw`` on each axis, dq and dw uniform within |dq| <= 1.75e-3 and
|dw| <= 1.75e-4 rad/s. On a turn about y the noise on q2 gives an angle error of about
2 dq / cos(theta / 2), up to 0.2 deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ._estimate import CommandLog, Estimate
from ._plant import Plant

IMU_QUATERNION_BOUND = 1.75e-3
IMU_RATE_BOUND_RAD_S = 1.75e-4


class Feedback(Protocol):
    """What the loop asks of a feedback source."""

    name: str

    def sample_times(self, t0_s: float, t1_s: float) -> list[float]: ...

    def observe(self, t_s: float, rot_ref_from_body: Rotation, rate_body_rad_s: NDArray) -> None: ...

    def estimate(self, t_s: float, plant: Plant, log: CommandLog) -> Estimate: ...


class TickFeedback:
    """Base of the sources read at every tick (they sample nothing during a plant step)."""

    name = "tick"

    def sample_times(self, t0_s: float, t1_s: float) -> list[float]:
        return []

    def observe(self, t_s: float, rot_ref_from_body: Rotation, rate_body_rad_s: NDArray) -> None:
        return None


class TruthFeedback(TickFeedback):
    """The true state, at every tick."""

    name = "truth"

    def estimate(self, t_s: float, plant: Plant, log: CommandLog) -> Estimate:
        return Estimate(t_s, plant.rot_ref_from_body(), plant.rate_body(), True)


@dataclass
class ImuFeedback(TickFeedback):
    """The true state with bounded uniform noise, at every tick.

    Parameters
    ----------
    rng : numpy Generator, seed or None
    quaternion_bound : float
        Half-width of the noise on each quaternion vector component.
    rate_bound_rad_s : float
        Half-width of the noise on each rate component, rad/s.
    """

    rng: np.random.Generator | int | None = None
    quaternion_bound: float = IMU_QUATERNION_BOUND
    rate_bound_rad_s: float = IMU_RATE_BOUND_RAD_S
    name: str = "imu"

    def __post_init__(self) -> None:
        for label in ("quaternion_bound", "rate_bound_rad_s"):
            value = getattr(self, label)
            if not (math.isfinite(value) and 0 <= value < 1):
                raise InvalidInputError(f"{label} must be in [0, 1), got {value!r}")
        self._generator = np.random.default_rng(self.rng)

    def estimate(self, t_s: float, plant: Plant, log: CommandLog) -> Estimate:
        q = plant.rot_ref_from_body().as_quat()
        vec = q[:3] + self._generator.uniform(-self.quaternion_bound, self.quaternion_bound, 3)
        scalar = math.copysign(math.sqrt(max(0.0, 1.0 - float(vec @ vec))), q[3])
        rate = plant.rate_body() + self._generator.uniform(-self.rate_bound_rad_s, self.rate_bound_rad_s, 3)
        return Estimate(t_s, Rotation.from_quat([*vec, scalar]), rate, True)

