"""Receding-horizon replanning (Sease 2013 ch. 5: a new path every 5 s from the current state).

At a new target, a path of ``tf_s`` (seed: 10 s) is planned from the estimated state; every
``replan_period_s`` (seed: 5 s) a new one starts from the estimate again. Two readings of the
seed's "varying final time which advances with each successive iteration":

* ``"shrinking"`` (default): the arrival time stays at target time + tf, each replan covers the
  time left; once it has passed, the plan holds the target, unless the estimate has drifted
  more than ``replan_error_deg`` from it, which starts a new tf-long path.
* ``"sliding"``: every replan looks tf ahead again (the arrival recedes while the error lasts).

When the current bound cannot be met in the horizon (a large slew), the horizon grows by
``growth`` until it can or reaches ``max_horizon_s`` (then the best path is flown and the
actuator saturates).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from ..errors import InvalidInputError, require
from ._cubesat import CubeSat
from ._planner import Boundary, PlannedPath, PlannerOptions, plan_path

HORIZONS = ("shrinking", "sliding")
MAX_START_Q2 = 0.7
"""Plans start from q2 clipped to this (the coil loses its authority at 1/sqrt 2)."""


@dataclass(frozen=True)
class GuidanceOptions:
    """Settings of the replanning (times in s)."""

    tf_s: float = 10.0
    replan_period_s: float = 5.0
    horizon: str = "shrinking"
    replan_error_deg: float = 2.0
    growth: float = 1.5
    max_horizon_s: float = 60.0
    planner: PlannerOptions = field(default_factory=PlannerOptions)

    def __post_init__(self) -> None:
        if self.horizon not in HORIZONS:
            raise InvalidInputError(f"horizon must be one of {', '.join(HORIZONS)}, got {self.horizon!r}")
        for name in ("tf_s", "replan_period_s", "replan_error_deg", "max_horizon_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InvalidInputError(f"{name} must be positive, got {value!r}")
        if not (math.isfinite(self.growth) and self.growth > 1):
            raise InvalidInputError(f"growth must be > 1, got {self.growth!r}")


@dataclass(frozen=True)
class PlanEvent:
    """One planning call: when, the horizon used, the outcome, the cost 1/2 int I^2 R dt (J) and SLSQP wall time (s)."""

    t_s: float
    horizon_s: float
    status: str
    cost_j: float
    wall_s: float


class Guidance:
    """Holds the current plan and decides when to replan."""

    def __init__(self, cubesat: CubeSat, options: GuidanceOptions | None = None):
        self.cubesat = cubesat
        self.options = options or GuidanceOptions()
        self.plan: PlannedPath | None = None
        self.events: list[PlanEvent] = []
        self._target: float | None = None
        self._arrival = -math.inf
        self._next_replan = -math.inf

    def update(self, t_s: float, theta_rad: float, omega_rad_s: float, target_q2: float) -> PlannedPath:
        """The plan to follow at ``t_s`` (replanned when due) for the estimated state."""
        opt = self.options
        if target_q2 != self._target:
            self._target = target_q2
            self._replan(t_s, theta_rad, omega_rad_s, opt.tf_s)
        elif t_s >= self._next_replan - 1e-9:
            remaining = self._arrival - t_s
            target_theta = 2.0 * math.asin(target_q2)
            if opt.horizon == "sliding":
                self._replan(t_s, theta_rad, omega_rad_s, opt.tf_s)
            elif remaining >= 0.5 * opt.replan_period_s:
                self._replan(t_s, theta_rad, omega_rad_s, remaining)
            elif abs(theta_rad - target_theta) > math.radians(opt.replan_error_deg):
                self._replan(t_s, theta_rad, omega_rad_s, opt.tf_s)
            else:
                self.plan = PlannedPath.hold(target_q2, t_s)
                self._next_replan = t_s + opt.replan_period_s
        return require(self.plan, "the guidance plan")

    def _replan(self, t_s: float, theta_rad: float, omega_rad_s: float, horizon_s: float) -> None:
        opt = self.options
        start_q2 = max(-MAX_START_Q2, min(MAX_START_Q2, math.sin(0.5 * theta_rad)))
        start, end = Boundary(start_q2, omega_rad_s), Boundary(require(self._target, "the guidance target"), 0.0)
        while True:
            wall = time.perf_counter()
            plan = plan_path(self.cubesat, start, end, t_s, horizon_s, opt.planner)
            self.events.append(PlanEvent(t_s, horizon_s, plan.status.value, plan.cost_j, time.perf_counter() - wall))
            if plan.feasible or horizon_s * opt.growth > opt.max_horizon_s:
                break
            horizon_s *= opt.growth
        self.plan = plan
        self._arrival = plan.t_end_s
        self._next_replan = t_s + opt.replan_period_s
