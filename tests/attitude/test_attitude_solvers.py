"""QUEST and the q-method against scipy's Rotation.align_vectors and known truth."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from wahba_problems import (
    align,
    angle_rad,
    cone_vectors,
    problems,
    random_unit_vectors,
)

from startrack.attitude import METHODS as ALL_METHODS
from startrack.attitude import esoq2, foam, olae, pad, q_method, quest, solve_wahba, svd_method, triad
from startrack.attitude._quest import quest_step
from startrack.attitude._wahba import attitude_profile_matrix, davenport_matrix
from startrack.frames import radec_roll_from_rotation, radec_to_vector, rotation_from_radec_roll
from startrack.results import Status
from startrack.units import ARCSEC, DEG, RAD

METHODS = [m for m in ALL_METHODS if m != "triad"]  # the solvers of the Wahba optimum
SOLVE_TOL = 1e-9 * RAD


@pytest.mark.parametrize("method", ALL_METHODS)
def test_known_rotation_maps_reference_onto_observed(method):
    # 90 degrees about z maps x to y and y to -x: the convention trap, checked by hand.
    reference = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    observed = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    rot = solve_wahba(observed, reference, method=method).rotation
    np.testing.assert_allclose(rot.apply(reference), observed, atol=1e-15)
    quat = rot.as_quat(canonical=True)
    np.testing.assert_allclose(quat, [0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-15)


@pytest.mark.parametrize("method", ALL_METHODS)
def test_rotation_is_rot_cam_from_icrs(method):
    # ICRS catalog vectors as reference, camera vectors as observed: the answer is the attitude.
    rng = np.random.default_rng(11)
    attitude = rotation_from_radec_roll(1.2, -0.4, 2.5)
    ra, dec = rng.uniform(0, 2 * np.pi, 8), rng.uniform(-1.5, 1.5, 8)
    catalog = radec_to_vector(ra, dec)
    result = solve_wahba(attitude.apply(catalog), catalog, method=method)
    assert angle_rad(result.rotation, attitude) < SOLVE_TOL
    radec_roll = radec_roll_from_rotation(result.rotation)
    np.testing.assert_allclose(radec_roll, (1.2, -0.4, 2.5), atol=1e-12)


@pytest.mark.parametrize("method", ALL_METHODS)
def test_noise_free_problems_recover_truth(method):
    rng = np.random.default_rng(1)
    truth = Rotation.random(200, random_state=rng)
    reference = random_unit_vectors((200, 6), rng)
    observed = problems(truth, reference, 0.0, rng)
    result = solve_wahba(observed, reference, method=method)
    assert np.max(angle_rad(result.rotation, truth)) < SOLVE_TOL
    assert np.max(angle_rad(result.rotation, align(observed, reference))) < SOLVE_TOL
    np.testing.assert_allclose(result.loss, 0.0, atol=1e-25)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("sigma_rad", [10 * ARCSEC, 1 * DEG])
def test_noisy_weighted_problems_match_align_vectors(method, sigma_rad):
    # Same optimum, so the two solvers agree to numerical precision, not to the noise level.
    rng = np.random.default_rng(2)
    truth = Rotation.random(200, random_state=rng)
    reference = random_unit_vectors((200, 7), rng)
    observed = problems(truth, reference, sigma_rad, rng)
    weights = rng.uniform(0.2, 5.0, size=(200, 7))
    result = solve_wahba(observed, reference, weights, method=method)
    assert np.max(angle_rad(result.rotation, align(observed, reference, weights))) < SOLVE_TOL
    assert np.median(angle_rad(result.rotation, truth)) > 1e-3 * sigma_rad  # the noise is real


@pytest.mark.parametrize("method", METHODS)
def test_star_tracker_field_matches_align_vectors(method):
    # Stars within 10 degrees of the boresight: K's top eigenvalues are close (roll is weak).
    rng = np.random.default_rng(3)
    truth = Rotation.random(300, random_state=rng)
    camera = cone_vectors((300, 10), 5 * DEG, rng)
    reference = np.einsum("mji,mnj->mni", truth.as_matrix(), camera)
    observed = problems(Rotation.identity(300), camera, 5 * ARCSEC, rng)
    result = solve_wahba(observed, reference, method=method)
    assert np.max(angle_rad(result.rotation, align(observed, reference))) < SOLVE_TOL


@pytest.mark.parametrize("method", ALL_METHODS)
def test_batched_equals_one_by_one(method):
    rng = np.random.default_rng(4)
    truth = Rotation.random(40, random_state=rng)
    reference = random_unit_vectors((40, 5), rng)
    observed = problems(truth, reference, 0.01, rng)
    weights = rng.uniform(0.5, 2.0, size=(40, 5))
    sigma = rng.uniform(0.005, 0.02, size=(40, 5))
    batch = solve_wahba(observed, reference, weights, method=method, sigma_rad=sigma)
    assert batch.rotation.as_quat().shape == (40, 4)
    for m in range(40):
        single = solve_wahba(
            observed[m], reference[m], weights[m], method=method, sigma_rad=sigma[m]
        )
        assert single.status is Status.OK and batch.status[m] is Status.OK
        assert angle_rad(single.rotation, batch.rotation[m]) < 1e-12 * RAD
        np.testing.assert_allclose(single.loss, batch.loss[m], rtol=1e-10)
        np.testing.assert_allclose(single.covariance_rad2, batch.covariance_rad2[m], rtol=1e-10)


def _axes():
    rng = np.random.default_rng(5)
    fixed = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1], [-1, 2, 0.5], [0, 1, -1]]
    axes = np.vstack([fixed, rng.normal(size=(6, 3))])
    return axes / np.linalg.norm(axes, axis=1, keepdims=True)


@pytest.mark.parametrize("method", ALL_METHODS)
@pytest.mark.parametrize("angle", [np.pi, np.pi - 1e-6, np.pi - 1e-3, 1e-6, 0.0])
def test_near_180_and_near_0_degree_rotations(method, angle):
    # QUEST and OLAE are singular at 180 degrees, ESOQ2 imprecise at 0: turned frames fix both.
    rng = np.random.default_rng(6)
    truth = Rotation.from_rotvec(angle * _axes())
    count = len(truth)
    reference = random_unit_vectors((count, 5), rng)
    exact = solve_wahba(problems(truth, reference, 0.0, rng), reference, method=method)
    assert np.max(angle_rad(exact.rotation, truth)) < SOLVE_TOL
    if method == "triad":
        return  # not the optimum of noisy data
    observed = problems(truth, reference, 1e-3, rng)
    noisy = solve_wahba(observed, reference, method=method)
    assert np.max(angle_rad(noisy.rotation, align(observed, reference))) < SOLVE_TOL


@pytest.mark.parametrize("method", ALL_METHODS)
@pytest.mark.parametrize("separation", [0.5 * DEG, 10 * DEG, 90 * DEG, 170 * DEG])
def test_two_vector_problems(method, separation):
    # A close pair is where plain QUEST (no refinement pass) is off by ~1e-7 rad.
    rng = np.random.default_rng(7)
    truth = Rotation.random(100, random_state=rng)
    first = random_unit_vectors((100,), rng)
    side = np.cross(first, random_unit_vectors((100,), rng))
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    second = np.cos(separation) * first + np.sin(separation) * side
    reference = np.stack([first, second], axis=1)
    exact = solve_wahba(problems(truth, reference, 0.0, rng), reference, method=method)
    assert np.max(angle_rad(exact.rotation, truth)) < SOLVE_TOL
    observed = problems(truth, reference, 20 * ARCSEC, rng)
    noisy = solve_wahba(observed, reference, [1.0, 3.0], method=method)
    if method == "triad":  # exact on its anchor (the heavier vector), not the optimum
        np.testing.assert_allclose(noisy.rotation.apply(reference[:, 1]), observed[:, 1], atol=1e-12)
        return
    scipy_answer = align(observed, reference, np.tile([1.0, 3.0], (100, 1)))
    assert np.max(angle_rad(noisy.rotation, scipy_answer)) < SOLVE_TOL


def test_per_method_functions_equal_the_dispatcher():
    rng = np.random.default_rng(8)
    reference = random_unit_vectors((6,), rng)
    observed = problems(Rotation.random(random_state=rng), reference, 0.01, rng)
    functions = [quest, q_method, svd_method, foam, esoq2, olae, pad, triad]
    for function, method in zip(functions, ALL_METHODS, strict=True):
        direct = function(observed, reference)
        dispatched = solve_wahba(observed, reference, method=method)
        assert angle_rad(direct.rotation, dispatched.rotation) == 0.0
        assert direct.loss == dispatched.loss


def test_loss_is_the_wahba_loss_with_the_callers_weights():
    rng = np.random.default_rng(9)
    reference = random_unit_vectors((8,), rng)
    observed = problems(Rotation.random(random_state=rng), reference, 0.02, rng)
    weights = rng.uniform(1.0, 4.0, 8)
    for method in METHODS:  # the optimum: any nearby rotation does worse
        result = solve_wahba(observed, reference, weights, method=method)
        residual = observed - result.rotation.apply(reference)
        expected = 0.5 * np.sum(weights * np.sum(residual**2, axis=1))
        assert result.loss == pytest.approx(expected, rel=1e-12)
        # The optimum: any nearby rotation does worse.
        for k in range(3):
            nudge = Rotation.from_rotvec(1e-4 * np.eye(3)[k]) * result.rotation
            worse = 0.5 * np.sum(weights * np.sum((observed - nudge.apply(reference)) ** 2, axis=1))
            assert worse > result.loss


@pytest.mark.parametrize("angle", [np.pi, np.pi - 1e-6])
def test_single_quest_solve_handles_180_degrees_by_sequential_rotations(angle):
    # One QUEST solve, before any refinement pass: only the turned frames make it accurate.
    rng = np.random.default_rng(10)
    truth = Rotation.from_rotvec(angle * _axes())
    reference = random_unit_vectors((len(truth), 5), rng)
    observed = problems(truth, reference, 0.0, rng)
    weights = np.full(reference.shape[:2], 1.0 / reference.shape[1])
    quat = quest_step(attitude_profile_matrix(observed, reference, weights))
    assert np.max(angle_rad(Rotation.from_quat(quat), truth)) < SOLVE_TOL


def test_davenport_matrix_pairs_with_scipy_quaternions():
    # q^T K q = tr(R(q) B^T) for any unit scalar-last q: K's layout and z's sign are scipy's.
    rng = np.random.default_rng(12)
    reference = random_unit_vectors((5,), rng)
    observed = random_unit_vectors((5,), rng)
    profile = attitude_profile_matrix(observed, reference, rng.uniform(0.1, 1.0, 5))
    k = davenport_matrix(profile)
    for rot in Rotation.random(20, random_state=rng):
        q = rot.as_quat()
        assert q @ k @ q == pytest.approx(np.trace(rot.as_matrix() @ profile.T), abs=1e-14)


def test_olae_gibbs_gives_nan_to_a_singular_problem_and_solves_the_others():
    # a batch with one pair of coincident directions raised LinAlgError ("Singular matrix") for the whole
    # batch: `startrack rate IMAGE --fov-deg 1e-300` ended as a fault of ours
    from startrack.attitude._olae import olae_gibbs

    turn = Rotation.from_rotvec([0.0, 0.0, 0.01])
    good = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    coincident = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    observed = np.stack([coincident, turn.apply(good)])
    reference = np.stack([coincident, good])
    gibbs = olae_gibbs(observed, reference, np.full((2, 2), 0.5))
    assert np.all(np.isnan(gibbs[0]))
    # the Gibbs vector of a turn by 0.01 rad about z is tan(0.005) z (rotation of reference onto observed,
    # up to the sign convention of OLAE's Gibbs vector): 1e-12 of it is rounding
    np.testing.assert_allclose(np.abs(gibbs[1]), [0.0, 0.0, np.tan(0.005)], atol=1e-12)
