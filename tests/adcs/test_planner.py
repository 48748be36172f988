"""The VMC planner: boundary conditions, the current bound, energy, and the plan flown open loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from startrack.adcs._cubesat import CubeSat
from startrack.adcs._planner import Boundary, PlannerOptions, PlanStatus, plan_path, prey_cubic
from startrack.adcs._plant import SingleAxisPlant
from startrack.errors import InvalidInputError

SAT = CubeSat()
DEG = math.pi / 180


@pytest.fixture(scope="module")
def step_plan():
    """A +0.1 step at the weak end of the range (q2 0.3 -> 0.4, cos theta down to 0.68), 10 s, from a small rate."""
    return plan_path(SAT, Boundary(0.3, 0.002), Boundary(0.4, 0.0), 5.0, 10.0)


def test_prey_cubic_meets_the_four_boundary_values():
    start, end, tf = Boundary(0.4, 0.015), Boundary(-0.3, 0.0), 10.0
    c = np.polynomial.Polynomial(prey_cubic(start, end, tf))
    assert c(0) == pytest.approx(start.q2) and c(tf) == pytest.approx(end.q2)
    assert c.deriv()(0) == pytest.approx(start.q2_dot) and c.deriv()(tf) == pytest.approx(end.q2_dot, abs=1e-15)


def test_plan_meets_its_boundary_conditions_and_the_current_bound(step_plan):
    plan = step_plan
    assert plan.status is PlanStatus.OK, plan.reason
    assert plan.nu[0] == 1.0 and plan.nu[-1] == 1.0
    theta0, rate0, _ = plan.sample(plan.t0_s)
    theta1, rate1, _ = plan.sample(plan.t_end_s - 1e-12)
    assert math.sin(theta0 / 2) == pytest.approx(0.3, abs=1e-12) and rate0 == pytest.approx(0.002, abs=1e-10)
    assert math.sin(theta1 / 2) == pytest.approx(0.4, abs=1e-12) and rate1 == pytest.approx(0.0, abs=1e-9)
    assert np.max(np.abs(plan.current_a)) <= SAT.max_current_a * (1 + 1e-6)
    assert np.all(np.abs(plan.q2) <= 1)


def test_plan_costs_no_more_than_its_prey(step_plan):
    prey_only = plan_path(SAT, Boundary(0.3, 0.002), Boundary(0.4, 0.0), 5.0, 10.0, PlannerOptions(max_iter=1))
    assert step_plan.cost_j <= prey_only.cost_j * (1 + 1e-9)
    # 1/2 int I^2 R dt by the LGL weights equals the trapezoid over the interpolated current to 1 %
    t = np.linspace(step_plan.t0_s, step_plan.t_end_s, 4001)
    current = np.interp(t, step_plan.times_s, step_plan.current_a)
    assert 0.5 * SAT.resistance_ohm * np.trapezoid(current**2, t) == pytest.approx(step_plan.cost_j, rel=0.05)


def test_plan_flown_open_loop_reaches_its_target(step_plan):
    """The nodal currents, interpolated and fed to the plant, land within 0.2 deg of the target at rest."""
    plan = step_plan
    plant = SingleAxisPlant(SAT, 2 * math.asin(0.3), 0.002, t0_s=plan.t0_s)
    dt = 0.005
    while plant.t_s < plan.t_end_s - 1e-9:
        current = float(np.interp(plant.t_s + dt / 2, plan.times_s, plan.current_a))
        plant.step([current], dt)
    assert plant.theta_rad == pytest.approx(2 * math.asin(0.4), abs=0.2 * DEG)
    assert plant.omega_rad_s == pytest.approx(0.0, abs=0.002)


def test_acceleration_of_the_sampled_path_is_the_derivative_of_its_rate(step_plan):
    t, h = step_plan.t0_s + 3.7, 1e-5
    _, _, accel = step_plan.sample(t)
    rate_slope = (step_plan.sample(t + h)[1] - step_plan.sample(t - h)[1]) / (2 * h)
    assert accel == pytest.approx(rate_slope, rel=1e-6)
    assert step_plan.sample(step_plan.t_end_s + 30.0) == pytest.approx((2 * math.asin(0.4), 0.0, 0.0))


def test_a_large_fast_slew_is_reported_infeasible_with_the_current_it_needs():
    """The seed's offline example, 0.4 -> -0.3 (82 deg) in 10 s, needs far more than 0.148 A with this coil."""
    plan = plan_path(SAT, Boundary(0.4, 0.0015), Boundary(-0.3, 0.0), 0.0, 10.0)
    assert plan.status is PlanStatus.INFEASIBLE and not plan.feasible
    assert "above the 0.148 A limit" in plan.reason
    assert plan_path(SAT, Boundary(0.4, 0.0015), Boundary(-0.3, 0.0), 0.0, 30.0).feasible


def test_refusals():
    with pytest.raises(InvalidInputError, match="tf_s"):
        plan_path(SAT, Boundary(0.1), Boundary(0.2), 0.0, 0.0)
    with pytest.raises(InvalidInputError, match="start.q2"):
        plan_path(SAT, Boundary(0.75), Boundary(0.2), 0.0, 10.0)
    with pytest.raises(InvalidInputError, match="q_ref"):
        PlannerOptions(q_ref=0.5)
    with pytest.raises(InvalidInputError, match="n_nodes"):
        PlannerOptions(n_nodes=3)
