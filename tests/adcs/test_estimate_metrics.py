"""Propagation of late measurements with the commanded accelerations; step metrics on known responses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.adcs._estimate import CommandLog, Measurement, estimate_from, y_angle
from startrack.adcs._metrics import overall_metrics, step_metrics
from startrack.adcs._plant import y_rotation


def _log(accels: list[tuple[float, float]]) -> CommandLog:
    log = CommandLog()
    for t, a in accels:
        log.append(t, np.array([0.0, a, 0.0]))
    return log


def test_propagation_is_exact_for_piecewise_constant_acceleration():
    """Attitude at 1.00 s, rate tagged 0.70 s, commands 0.02 rad/s^2 from 0.5 s and -0.01 from 1.2 s."""
    log = _log([(0.0, 0.0), (0.5, 0.02), (1.2, -0.01)])

    def truth(t):  # theta(t), w(t) with theta(1) = 0.1 and w(0.7) = 0.03
        w07 = 0.03
        w = w07 + 0.02 * (min(t, 1.2) - 0.7) - 0.01 * max(0.0, t - 1.2)
        theta_1 = 0.1
        # integrate w from 1.0 to t
        w1 = w07 + 0.02 * 0.3
        if t <= 1.2:
            return theta_1 + w1 * (t - 1.0) + 0.01 * (t - 1.0) ** 2, w
        w12 = w07 + 0.02 * 0.5
        return theta_1 + w1 * 0.2 + 0.01 * 0.04 + w12 * (t - 1.2) - 0.005 * (t - 1.2) ** 2, w

    m = Measurement(1.0, 0.7, 1.05, y_rotation(0.1), np.array([0.0, 0.03, 0.0]))
    for t in (1.05, 1.2, 1.6):
        est = estimate_from(log, m, t)
        theta, w = truth(t)
        assert est.valid and est.age_s == pytest.approx(t - 1.0)
        assert est.theta_rad == pytest.approx(theta, abs=1e-12) and est.omega_rad_s == pytest.approx(w, abs=1e-12)


def test_no_measurement_gives_an_invalid_estimate_and_y_angle_reads_a_y_turn():
    assert not estimate_from(CommandLog(), None, 3.0).valid
    for theta in (-1.0, 0.0, 0.7, 2.5):
        assert y_angle(y_rotation(theta)) == pytest.approx(theta, abs=1e-12)
    tilted = Rotation.from_rotvec([0.0, 0.3, 0.0]) * Rotation.from_rotvec([0.01, 0.0, 0.0])
    assert y_angle(tilted) == pytest.approx(0.3, abs=1e-4)


def test_metrics_of_a_ramp_and_of_a_damped_response():
    t = np.arange(0.0, 100.0, 0.025)
    ramp = np.clip(t / 10.0, 0.0, 1.0)  # 0 -> 1 rad linearly in 10 s
    m = step_metrics(t, ramp, np.full(t.size, 0.02), 1.0, t_start_s=0.0, target_q2=math.sin(0.5), complete=True)
    assert m.rise_time_s == pytest.approx(8.0, abs=0.03)
    assert m.overshoot_pct == 0.0
    assert m.settling_time_s == pytest.approx(9.5, abs=0.03)
    assert m.steady_state_error_deg == 0.0 and m.avg_power_w == pytest.approx(0.02)
    zeta, wn = 0.5, 1.0  # second-order step: overshoot exp(-pi zeta / sqrt(1 - zeta^2)) = 16.3 %
    wd = wn * math.sqrt(1 - zeta**2)
    response = 1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
    d = step_metrics(t, response, np.zeros(t.size), 1.0, t_start_s=0.0, target_q2=0.0, complete=True)
    assert d.overshoot_pct == pytest.approx(100 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)), abs=0.05)
    assert d.settling_time_s == pytest.approx(5.3, abs=0.3)  # 5 % band: ~3 / (zeta wn), refined by the ripple
    assert d.rise_time_s == pytest.approx(1.64, abs=0.05)


def test_overall_takes_the_worst_and_a_missing_value_is_the_worst():
    t = np.arange(0.0, 100.0, 0.025)
    good = step_metrics(t, np.clip(t / 9, 0, 1), np.ones(t.size), 1.0, t_start_s=0.0, target_q2=0.0, complete=True)
    never = step_metrics(t, np.clip(t / 1000, 0, 1), np.ones(t.size), 1.0, t_start_s=100.0, target_q2=0.0,
                         complete=True)
    overall = overall_metrics([good, never], np.ones(10))
    assert math.isnan(overall.rise_time_s) and math.isnan(overall.settling_time_s)
    assert not overall.meets_table_5_3() and good.meets_table_5_3()
    assert overall.to_dict()["rise_time_s"] is None
