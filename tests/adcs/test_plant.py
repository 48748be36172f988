"""Plants against invariants and each other; fields against the dipole formula; allocation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.adcs._actuation import allocate
from startrack.adcs._cubesat import CubeSat, helmholtz_field_t
from startrack.adcs._field import EARTH_RADIUS_M, DipoleField, UniformField, dipole_field_t
from startrack.adcs._plant import SingleAxisPlant, ThreeAxisPlant, y_rotation
from startrack.errors import InvalidInputError

SAT = CubeSat()


def test_coil_torque_is_n_a_b_i_times_one_minus_two_q2_squared():
    plant = SingleAxisPlant(SAT)
    for theta in (0.0, 0.5, -0.9):
        q2 = math.sin(theta / 2)
        expected = 80 * 0.0064 * 4.5e-4 * 0.1 * (1 - 2 * q2 * q2) / SAT.j22
        assert plant.accel_rad_s2(theta, 0.1) == pytest.approx(expected, rel=1e-12)
    assert SAT.max_accel_rad_s2 == pytest.approx(80 * 0.0064 * 4.5e-4 * 0.148 / 1.05e-3, rel=1e-12)


def test_single_axis_integration_keeps_its_first_integral():
    """theta'' = k cos(theta) with k constant conserves w^2 / 2 - k sin(theta)."""
    plant = SingleAxisPlant(SAT, theta0_rad=-0.4, omega0_rad_s=0.01)
    k = SAT.moment_per_amp * SAT.field_t * 0.1 / SAT.j22
    first = 0.5 * plant.omega_rad_s**2 - k * math.sin(plant.theta_rad)
    for _ in range(400):
        plant.step([0.1], 0.025)
    assert plant.t_s == pytest.approx(10.0)
    assert plant.theta_rad > -0.4 + 0.1
    assert 0.5 * plant.omega_rad_s**2 - k * math.sin(plant.theta_rad) == pytest.approx(first, rel=1e-7)


def test_three_axis_plant_with_the_z_coil_matches_the_single_axis_plant():
    one = SingleAxisPlant(SAT, 0.2, 0.003)
    three = ThreeAxisPlant(SAT, UniformField((SAT.field_t, 0.0, 0.0)), y_rotation(0.2), (0.0, 0.003, 0.0))
    samples = []
    for k in range(200):
        current = 0.12 * math.sin(k / 30)
        samples.append((one.step([current], 0.025, [one.t_s + 0.01]), three.step([0, 0, current], 0.025,
                                                                                 [three.t_s + 0.01])))
    assert y_rotation(one.theta_rad).inv() * three.rot_ref_from_body() is not None
    assert (y_rotation(one.theta_rad).inv() * three.rot_ref_from_body()).magnitude() < 1e-9
    np.testing.assert_allclose(three.rate_body(), one.rate_body(), atol=1e-10)
    (rot1, rate1), = samples[-1][0]
    (rot3, rate3), = samples[-1][1]
    assert (rot1.inv() * rot3).magnitude() < 1e-9 and rate1 == pytest.approx(rate3, abs=1e-10)


def test_states_inside_a_step_are_returned_in_the_order_asked():
    plant = SingleAxisPlant(SAT, 0.0, 0.01)
    out = plant.step([0.0], 0.1, [0.05, 0.0, 0.1])
    assert [round(float(r.as_rotvec()[1]), 9) for r, _ in out] == [0.0005, 0.0, 0.001]
    with pytest.raises(InvalidInputError, match="t_eval"):
        plant.step([0.0], 0.1, [0.5])
    with pytest.raises(InvalidInputError, match="currents_a"):
        plant.step([0.0, 1.0], 0.1)


def test_dipole_field_at_the_equator_and_the_poles():
    b0 = 1e-7 * 7.94e22 / EARTH_RADIUS_M**3
    equator = dipole_field_t([EARTH_RADIUS_M, 0.0, 0.0])
    pole = dipole_field_t([0.0, 0.0, EARTH_RADIUS_M])
    np.testing.assert_allclose(equator, [0.0, 0.0, b0], rtol=1e-12)  # northward at the equator
    np.testing.assert_allclose(pole, [0.0, 0.0, -2 * b0], rtol=1e-12)  # downward at the north pole
    assert 2.9e-5 < b0 < 3.2e-5
    orbit = DipoleField(altitude_km=500.0, inclination_deg=90.0)
    assert orbit.period_s / 60 == pytest.approx(94.47, abs=0.05)  # 500 km above the mean radius
    strength = np.linalg.norm(orbit.field_ref(np.linspace(0, orbit.period_s, 50)), axis=1)
    ratio = (EARTH_RADIUS_M / orbit.radius_m) ** 3
    assert strength.min() == pytest.approx(b0 * ratio, rel=1e-3) and strength.max() == pytest.approx(2 * b0 * ratio,
                                                                                                      rel=1e-3)


def test_helmholtz_field_of_the_seed_test_bed():
    """Seed eq. 5.34 with the measured 9.98 G at 2.19 A: about 0.99 A gives the 4.5 G used."""
    per_amp = 9.98e-4 / 2.19
    assert helmholtz_field_t(100, 1.0, 0.15) == pytest.approx(0.8**1.5 * 4e-7 * math.pi * 100 / 0.15)
    assert 4.5e-4 / per_amp == pytest.approx(0.99, abs=0.01)


def test_allocation_single_coil_and_three_coils():
    b = np.array([SAT.field_t * math.cos(0.4), 0.0, SAT.field_t * math.sin(0.4)])
    coil = np.array([[0.0, 0.0, 1.0]])
    currents, torque = allocate(SAT, coil, b, np.array([0.0, 0.01, 0.0]))
    assert torque[1] == pytest.approx(SAT.j22 * 0.01, rel=1e-12)
    currents_pd, _ = allocate(SAT, coil, b, np.array([0.0, 0.01, 0.0]), field_compensated=False)
    assert currents_pd[0] == pytest.approx(currents[0] * math.cos(0.4), rel=1e-12)
    saturated, _ = allocate(SAT, coil, b, np.array([0.0, 1.0, 0.0]))
    assert saturated[0] == SAT.max_current_a
    want = np.array([0.002, -0.004, 0.001])
    three, torque3 = allocate(SAT, np.eye(3), b, want)
    wanted_torque = np.asarray(SAT.inertia_kg_m2) * want
    normal = wanted_torque - (wanted_torque @ b) / (b @ b) * b  # the part the coils can make
    np.testing.assert_allclose(torque3, normal, rtol=1e-10, atol=1e-15)
    assert np.max(np.abs(three)) <= SAT.max_current_a


def test_cubesat_parameters_and_refusals():
    assert CubeSat.seed_printed().j22 == pytest.approx(1.05e-2)
    assert CubeSat().with_j22(2e-3).inertia_kg_m2 == pytest.approx((2e-3 * 1.10 / 1.05, 2e-3, 2e-3 * 0.99 / 1.05))
    with pytest.raises(InvalidInputError, match="inertia_kg_m2"):
        CubeSat(inertia_kg_m2=(1.0, -1.0, 1.0))
    with pytest.raises(InvalidInputError, match="coil_area_m2"):
        CubeSat(coil_area_m2=0.0)
    with pytest.raises(InvalidInputError, match="b_ref_t"):
        UniformField((0.0, 0.0, 0.0))
    assert isinstance(y_rotation(0.1), Rotation)
