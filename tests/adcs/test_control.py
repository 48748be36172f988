"""LQR gain against the Riccati equation and the closed form; the error and its linearisation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from startrack.adcs._control import (
    A_DOUBLE_INTEGRATOR,
    B_DOUBLE_INTEGRATOR,
    LQRTracking,
    PDTracking,
    lqr_gain,
    tracking_error,
    tracking_law,
)
from startrack.errors import InvalidInputError


def test_lqr_gain_solves_the_riccati_equation_with_the_seed_weights():
    lqr = lqr_gain(20.0, 1.0)
    a, b, p = A_DOUBLE_INTEGRATOR, B_DOUBLE_INTEGRATOR, lqr.riccati
    residual = a.T @ p + p @ a - p @ b @ b.T @ p + 20.0 * np.eye(2)
    np.testing.assert_allclose(residual, 0.0, atol=1e-10)
    np.testing.assert_allclose(lqr.gain, b.T @ p, rtol=1e-12)
    assert np.all(np.linalg.eigvals(p) > 0)
    # closed form of the double integrator: k_angle = sqrt(q / r), k_rate = sqrt(q / r + 2 k_angle)
    assert lqr.k_angle == pytest.approx(math.sqrt(20.0), rel=1e-10)
    assert lqr.k_rate == pytest.approx(math.sqrt(20.0 + 2.0 * math.sqrt(20.0)), rel=1e-10)
    closed = np.linalg.eigvals(a - b @ lqr.gain)
    assert np.all(closed.real < 0)


def test_other_weights_and_refusals():
    lqr = lqr_gain(5.0, 2.0)
    assert lqr.k_angle == pytest.approx(math.sqrt(2.5), rel=1e-10)
    with pytest.raises(InvalidInputError, match="r_weight"):
        lqr_gain(20.0, 0.0)
    with pytest.raises(InvalidInputError, match="law"):
        tracking_law("pid")


@pytest.mark.parametrize(("theta", "phi"), [(0.1, 0.3), (-0.6, -0.2), (0.8, 0.79)])
def test_error_quaternion_gives_the_sine_of_the_angle_difference(theta, phi):
    e, e_dot = tracking_error(theta, 0.01, phi, 0.03)
    assert e == pytest.approx(math.sin(phi - theta), abs=1e-15)
    assert e_dot == pytest.approx(math.cos(phi - theta) * 0.02, abs=1e-15)


def test_input_output_linearisation_makes_the_error_a_double_integrator():
    """With the commanded w', the error's second derivative (finite differences) is v = -K x."""
    law = tracking_law("lqr")
    assert isinstance(law, LQRTracking)
    theta, omega = 0.31, 0.012
    phi, phi_dot, phi_ddot = 0.35, 0.02, -0.004
    accel = law.accel(theta, omega, (phi, phi_dot, phi_ddot))
    h = 1e-3

    def e_at(s):
        return tracking_error(theta + omega * s + 0.5 * accel * s * s, 0.0,
                              phi + phi_dot * s + 0.5 * phi_ddot * s * s, 0.0)[0]

    e_ddot = (e_at(h) - 2 * e_at(0.0) + e_at(-h)) / h**2
    e, e_dot = tracking_error(theta, omega, phi, phi_dot)
    v = -(law.lqr.k_rate * e_dot + law.lqr.k_angle * e)
    assert e_ddot == pytest.approx(v, rel=1e-4)


def test_pd_baseline_uses_the_lqr_gains_without_feed_forward():
    pd = tracking_law("pd")
    assert isinstance(pd, PDTracking) and not pd.field_compensated
    lqr = lqr_gain()
    assert pd.accel(0.0, 0.0, (0.01, 0.0, 5.0)) == pytest.approx(lqr.k_angle * 0.01)
    assert pd.accel(0.0, 0.0, (0.0, 0.002, 0.0)) == pytest.approx(lqr.k_rate * 0.002)
