"""The seed's run (Sease 2013 ch. 5, Fig. 5.7-5.11): seven steps of +0.1 in q2, one every 100 s.

From rest at q2 = -0.3, the target becomes -0.2 at t = 0, -0.1 at 100 s, ... and 0.4 at 600 s:
seven steps from -0.3 to 0.4 over 700 s, as in the seed's hardware run ("7 attitude maneuvers
from q2 = -0.3 to 0.4"). Control at 40 Hz.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InvalidInputError

MAX_TICKS = 10_000_000
"""The most control ticks a run takes (69 h at 40 Hz): a run keeps 15 values of 8 bytes per tick
(its time and the series of :data:`startrack.adcs._loop.RECORDED`), 1.2 GB at this length."""


@dataclass(frozen=True)
class Scenario:
    """Initial state, the step targets and the run's length (times in s, rates in rad/s)."""

    q2_start: float = -0.3
    omega_start_rad_s: float = 0.0
    step_q2: float = 0.1
    n_steps: int = 7
    step_period_s: float = 100.0
    duration_s: float = 700.0
    control_rate_hz: float = 40.0

    def __post_init__(self) -> None:
        for name in ("step_period_s", "duration_s", "control_rate_hz"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InvalidInputError(f"{name} must be positive, got {value!r}")
        if not 1 <= self.duration_s * self.control_rate_hz <= MAX_TICKS:
            raise InvalidInputError(f"duration_s must hold 1 to {MAX_TICKS:,} control ticks of {self.dt_s:g} s "
                                    f"({self.dt_s:g} to {MAX_TICKS * self.dt_s:,.0f} s; a run keeps every tick "
                                    f"in memory), got {self.duration_s!r}")
        if not (isinstance(self.n_steps, int | np.integer) and self.n_steps >= 1):
            raise InvalidInputError(f"n_steps must be a whole number >= 1, got {self.n_steps!r}")
        last = self.q2_start + self.n_steps * self.step_q2
        for name, q2 in (("q2_start", self.q2_start), ("the last target", last)):
            if not abs(q2) < math.sqrt(0.5):
                raise InvalidInputError(f"{name} ({q2:g}) must lie in (-0.707, 0.707), where the coil acts")

    @property
    def dt_s(self) -> float:
        return 1.0 / self.control_rate_hz

    @property
    def n_ticks(self) -> int:
        return int(math.floor(self.duration_s * self.control_rate_hz + 1e-9))

    def steps(self) -> list[tuple[float, float]]:
        """(start time s, target q2) of the steps that begin within the run."""
        return [(k * self.step_period_s, self.q2_start + (k + 1) * self.step_q2)
                for k in range(self.n_steps) if k * self.step_period_s < self.duration_s]

    def target_at(self, t_s: float) -> float:
        """The target q2 at ``t_s``."""
        k = min(self.n_steps - 1, max(0, int(math.floor(t_s / self.step_period_s + 1e-9))))
        return self.q2_start + (k + 1) * self.step_q2
