"""Averaging, propagation, relative-attitude chaining, mounting and the predictive update."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from wahba_problems import angle_rad, cone_vectors, perturb

from startrack.attitude import (
    attitude_scatter,
    average_quaternions,
    average_rotations,
    body_attitude,
    camera_attitude,
    chain_relative,
    covariance_to_body,
    estimate_mounting,
    predictive_update,
    propagate,
    propagate_steps,
    quaternion_derivative,
    relative_attitude,
    solve_wahba,
    to_body,
)
from startrack.errors import InvalidInputError
from startrack.units import ARCSEC, DEG, RAD


def test_average_equals_scipy_mean_and_ignores_signs():
    rng = np.random.default_rng(50)
    centre = Rotation.random(random_state=rng)
    spread = Rotation.from_rotvec(rng.normal(scale=0.1, size=(30, 3))) * centre
    weights = rng.uniform(0.5, 2.0, 30)
    ours = average_rotations(spread, weights)
    assert angle_rad(ours, spread.mean(weights)) < 1e-12 * RAD
    flipped = spread.as_quat() * rng.choice([-1.0, 1.0], size=(30, 1))
    again = Rotation.from_quat(average_quaternions(flipped, weights))
    assert angle_rad(again, ours) < 1e-12 * RAD


def test_batched_average_and_scatter():
    rng = np.random.default_rng(51)
    truth = Rotation.random(4, random_state=rng)
    noise = Rotation.from_rotvec(rng.normal(scale=10 * ARCSEC, size=(4, 400, 3)).reshape(-1, 3))
    samples = noise * Rotation.from_quat(np.repeat(truth.as_quat(), 400, axis=0))
    mean = Rotation.from_quat(average_quaternions(samples.as_quat().reshape(4, 400, 4)))
    assert np.max(angle_rad(mean, truth)) < 3 * ARCSEC  # 10 arcsec / sqrt(400) * ~sqrt(3) * 3
    scatter = attitude_scatter(samples[:400], mean[0])
    np.testing.assert_allclose(np.diag(scatter), (10 * ARCSEC) ** 2, rtol=0.25)


@pytest.mark.parametrize("bad", [np.zeros((3, 3)), np.zeros((0, 4)), np.zeros((2, 4))])
def test_average_rejects_bad_quaternions(bad):
    with pytest.raises(InvalidInputError, match="quaternions"):
        average_quaternions(bad)


def test_propagation_matches_the_kinematics_by_finite_difference():
    # dA/dt = -[w x] A: the closed form and the quaternion derivative agree.
    rng = np.random.default_rng(52)
    start = Rotation.random(random_state=rng)
    omega = np.array([0.02, -0.05, 0.01])
    h = 1e-4
    ahead, behind = propagate(start, omega, h), propagate(start, omega, -h)
    dq = (ahead.as_quat() - behind.as_quat()) / (2 * h)
    np.testing.assert_allclose(dq, quaternion_derivative(start.as_quat(), omega), atol=1e-9)
    d_matrix = (ahead.as_matrix() - behind.as_matrix()) / (2 * h)
    skew = np.array([[0, -omega[2], omega[1]], [omega[2], 0, -omega[0]], [-omega[1], omega[0], 0]])
    np.testing.assert_allclose(d_matrix, -skew @ start.as_matrix(), atol=1e-9)


def test_camera_frame_rate_moves_stars_and_icrs_rate_equals_turned_camera_rate():
    rng = np.random.default_rng(53)
    start = Rotation.random(random_state=rng)
    omega_cam = np.array([0.0, 0.1, 0.0])  # about camera y: stars move along camera -x
    later = propagate(start, omega_cam, 1.0)
    star = start.inv().apply([0.0, 0.0, 1.0])  # on the boresight at t = 0
    moved = later.apply(star)
    assert moved[0] == pytest.approx(-np.sin(0.1)) and moved[1] == pytest.approx(0.0, abs=1e-15)
    omega_icrs = start.inv().apply(omega_cam)  # a constant rate is the same axis in both frames
    by_icrs = propagate(start, omega_icrs, np.array([0.5, 1.0]), frame="icrs")
    assert np.max(angle_rad(by_icrs[1], later)) < 1e-14 * RAD
    steps = propagate_steps(start, np.tile(omega_cam, (4, 1)), 0.25)
    assert len(steps) == 5 and angle_rad(steps[-1], later) < 1e-14 * RAD


def test_relative_chain_reproduces_attitudes_and_grows_errors_in_quadrature():
    rng = np.random.default_rng(54)
    attitudes = propagate(Rotation.random(random_state=rng), [0.01, 0.02, -0.03], np.arange(6.0))
    deltas = relative_attitude(attitudes[:-1], attitudes[1:])
    chained, covs = chain_relative(attitudes[0], deltas, np.eye(3) * 4e-10, np.eye(3) * 1e-10)
    assert np.max(angle_rad(chained, attitudes)) < 1e-14 * RAD
    # eps_j^2 = eps_i^2 + eps_ij^2 (Huffman 2006 eq. 7.1): isotropic traces add.
    np.testing.assert_allclose(np.trace(covs, axis1=1, axis2=2), 3e-10 * (4 + np.arange(6)), rtol=1e-12)
    assert chain_relative(attitudes[0], deltas)[1] is None


def test_chained_covariance_matches_monte_carlo():
    rng = np.random.default_rng(55)
    start = Rotation.random(random_state=rng)
    deltas = Rotation.from_rotvec(rng.normal(scale=0.5, size=(3, 3)))
    q = np.diag([1.0, 4.0, 9.0]) * 1e-8
    _, covs = chain_relative(start, deltas, None, q)
    truth = chain_relative(start, deltas)[0][-1]
    final = Rotation.from_quat(np.tile(start.as_quat(), (3000, 1)))
    for delta in deltas:  # the same chain with noisy steps, 3000 times at once
        final = Rotation.from_rotvec(rng.multivariate_normal(np.zeros(3), q, size=3000)) * delta * final
    errors = (truth * final.inv()).as_rotvec()
    np.testing.assert_allclose(np.cov(errors, rowvar=False), covs[-1], atol=0.1 * np.max(covs[-1]))


def test_mounting_round_trip_and_estimate():
    rng = np.random.default_rng(56)
    mount = Rotation.from_euler("xyz", [90, 0, 30], degrees=True)  # rot_cam_from_body
    body = Rotation.random(20, random_state=rng)
    cam = camera_attitude(body, mount)
    assert np.max(angle_rad(body_attitude(cam, mount), body)) < 1e-14 * RAD
    noisy = Rotation.from_rotvec(rng.normal(scale=5 * ARCSEC, size=(20, 3))) * cam
    assert angle_rad(estimate_mounting(noisy, body), mount) < 5 * ARCSEC
    omega_cam = np.array([0.0, 0.0, 0.1])
    np.testing.assert_allclose(mount.apply(to_body(omega_cam, mount)), omega_cam, atol=1e-15)
    cov = np.diag([1.0, 1.0, 25.0])
    body_cov = covariance_to_body(cov, mount)
    assert np.trace(body_cov) == pytest.approx(27.0)
    np.testing.assert_allclose(mount.as_matrix() @ body_cov @ mount.as_matrix().T, cov, atol=1e-12)


def test_predictive_update_recovers_rate_and_handles_anisotropic_errors():
    # Huffman 2006 §6.1.2: the model error d is the rate carrying A(t_k) to the attitude at t_k+1.
    rng = np.random.default_rng(57)
    start = Rotation.random(random_state=rng)
    omega = np.array([0.002, -0.001, 0.003])
    dt = 0.5
    camera = cone_vectors((12,), 6 * DEG, rng)
    later = propagate(start, omega, dt)
    catalog = later.inv().apply(camera)
    update = predictive_update(start, perturb(camera, 1 * ARCSEC, rng), catalog, dt, sigma_rad=1 * ARCSEC)
    assert angle_rad(update.rotation, later) < 10 * ARCSEC
    np.testing.assert_allclose(update.omega_rad_s, omega, atol=20 * ARCSEC / dt)
    quest_cov = solve_wahba(camera, catalog, sigma_rad=1 * ARCSEC).covariance_rad2
    np.testing.assert_allclose(update.covariance_rad2, quest_cov, rtol=0.05, atol=0.01 * np.max(quest_cov))
    # Anisotropic: errors only along camera x -> the x-tilt information is unlimited, but
    # full covariances are accepted and give a finite covariance.
    tangent_cov = np.stack([np.diag([4.0, 1.0, 0.0]) * ARCSEC**2] * 12)
    aniso = predictive_update(start, camera, catalog, dt, measurement_cov_rad2=tangent_cov)
    assert np.all(np.isfinite(aniso.covariance_rad2))
    assert aniso.covariance_rad2[1, 1] > aniso.covariance_rad2[0, 0]  # tilt about y: x errors
    with pytest.raises(InvalidInputError, match="dt_s"):
        predictive_update(start, camera, catalog, 0.0)
