"""Step-response metrics of a run, per step and overall (Sease 2013 Table 5.3's quantities).

For step k, over its window [t_k, t_k + period) and on the **true** angle theta about y, with
``delta = theta_target - theta(t_k)``:

* rise time: from the first crossing of 10 % of delta to the first crossing of 90 %, s;
* overshoot: the largest excursion past the target along delta, % of |delta|;
* settling time: from t_k to the last instant outside the band ``settle_fraction |delta|``
  (5 % by default) around the target, s (NaN if still outside at the window's end);
* steady-state error: the largest |theta - theta_target| over the window's last
  ``steady_window_s`` (20 s by default), deg;
* average and peak coil power ``sum I^2 R`` of the delivered currents, W.

Overall: the largest of each over the complete steps (the seed's Table 5.3 gives upper bounds
over its steps), a NaN (not reached / not settled) counting as the worst, and the average power
over the whole run.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from ._loop import RunRecord

METRIC_KEYS = ("steady_state_error_deg", "overshoot_pct", "rise_time_s", "settling_time_s", "avg_power_w",
               "peak_power_w")
SEED_TABLE_5_3 = {"steady_state_error_deg": 4.5, "overshoot_pct": 20.0, "rise_time_s": 8.0, "settling_time_s": 30.0}
"""Sease 2013 Table 5.3: upper bounds from the hardware run."""
SEED_POWER_W = {"avg_power_w": 0.10, "peak_power_w": 0.5, "pid_avg_power_w": 0.15, "adaptive_avg_power_w": 0.66}
"""Sease 2013 p. 75: the hardware run's power (about 0.10 W average, 0.5 W peak) and the PID and
adaptive controllers' averages on the same test bed."""


@dataclass(frozen=True)
class StepMetrics:
    """Metrics of one step (or of the run, as ``overall``); NaN where not reached."""

    steady_state_error_deg: float
    overshoot_pct: float
    rise_time_s: float
    settling_time_s: float
    avg_power_w: float
    peak_power_w: float
    t_start_s: float = math.nan
    target_q2: float = math.nan
    complete: bool = True

    def to_dict(self) -> dict:
        """JSON-ready: NaN becomes None."""
        return {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in asdict(self).items()}

    def meets_table_5_3(self) -> bool:
        return all(getattr(self, k) < bound for k, bound in SEED_TABLE_5_3.items())


def step_metrics(t_s: NDArray, theta: NDArray, power_w: NDArray, target_theta: float, *, t_start_s: float,
                 target_q2: float, complete: bool, settle_fraction: float = 0.05,
                 steady_window_s: float = 20.0) -> StepMetrics:
    """Metrics of one step from its window's times (s), true angles (rad) and powers (W)."""
    rel = t_s - t_start_s
    delta = float(target_theta - theta[0])
    size = abs(delta)
    progress = (theta - theta[0]) / delta if size > 0 else np.ones_like(theta)
    rise = _first(rel, progress >= 0.9) - _first(rel, progress >= 0.1)
    past = float(np.max((theta - target_theta) * math.copysign(1.0, delta)))
    overshoot = max(0.0, past) / size * 100.0 if size else 0.0
    outside = np.abs(theta - target_theta) > settle_fraction * size
    settle = math.nan if outside[-1] else (float(rel[np.nonzero(outside)[0][-1] + 1]) if outside.any() else 0.0)
    tail = rel >= rel[-1] - steady_window_s + 1e-9
    steady = math.degrees(float(np.max(np.abs(theta[tail] - target_theta)))) if rel[-1] >= steady_window_s else math.nan
    return StepMetrics(steady, overshoot, rise, settle, float(np.mean(power_w)), float(np.max(power_w)),
                       t_start_s, target_q2, complete)


def _first(rel: NDArray, mask: NDArray) -> float:
    hits = np.nonzero(mask)[0]
    return float(rel[hits[0]]) if hits.size else math.nan


def run_metrics(record: RunRecord, settle_fraction: float = 0.05, steady_window_s: float = 20.0
                ) -> tuple[list[StepMetrics], StepMetrics]:
    """Per-step metrics of a run and the overall ones."""
    sc = record.config.scenario
    steps = []
    for t0, q2 in sc.steps():
        t1 = t0 + sc.step_period_s
        inside = (record.t_s >= t0 - 1e-9) & (record.t_s < t1 - 1e-9)
        if inside.sum() < 2:
            continue
        steps.append(step_metrics(record.t_s[inside], record.theta_true[inside], record.power_w[inside],
                                  2.0 * math.asin(q2), t_start_s=t0, target_q2=q2,
                                  complete=bool(record.t_s[-1] + sc.dt_s >= t1 - 1e-9),
                                  settle_fraction=settle_fraction, steady_window_s=steady_window_s))
    return steps, overall_metrics(steps, record.power_w)


def overall_metrics(steps: list[StepMetrics], power_w: NDArray) -> StepMetrics:
    """The worst of each metric over the complete steps (all steps if none is complete)."""
    chosen = [s for s in steps if s.complete] or steps
    worst = {k: _worst([getattr(s, k) for s in chosen]) for k in METRIC_KEYS[:4]}
    return StepMetrics(**worst, avg_power_w=float(np.mean(power_w)), peak_power_w=float(np.max(power_w)),
                       complete=all(s.complete for s in steps))


def _worst(values: list[float]) -> float:
    return math.nan if not values or any(math.isnan(v) for v in values) else max(values)
