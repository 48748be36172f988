"""QUEST covariance: closed forms, and a chi-square check of the frame and the factor of 4."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from scipy.spatial.transform import Rotation
from wahba_problems import cone_vectors, perturb, random_unit_vectors

from startrack.attitude import METHODS, attitude_covariance, roll_cross_boresight, solve_wahba
from startrack.errors import InvalidInputError
from startrack.units import ARCSEC, DEG

TRIALS, STARS = 2000, 8


def test_orthogonal_triad_closed_form():
    # F = sum (1/s_i^2)(I - e_i e_i^T) is diagonal: P_xx = 1 / (1/s_y^2 + 1/s_z^2), etc.
    sx, sy, sz = 1 * ARCSEC, 2 * ARCSEC, 4 * ARCSEC
    cov = attitude_covariance(np.eye(3), [sx, sy, sz])
    expected = np.diag([1 / (sy**-2 + sz**-2), 1 / (sx**-2 + sz**-2), 1 / (sx**-2 + sy**-2)])
    np.testing.assert_allclose(cov, expected, rtol=1e-12)
    # Equal sigmas: sigma^2 / 2 per axis (the seed's P_QQ would be sigma^2 / 8).
    equal = attitude_covariance(np.eye(3), sx)
    np.testing.assert_allclose(equal, np.eye(3) * sx**2 / 2, rtol=1e-12)


def test_covariance_is_a_camera_frame_tensor():
    rng = np.random.default_rng(30)
    observed = cone_vectors((6,), 8 * DEG, rng)
    sigma = rng.uniform(1, 5, 6) * ARCSEC
    turn = Rotation.random(random_state=rng)
    cov = attitude_covariance(observed, sigma)
    turned = attitude_covariance(turn.apply(observed), sigma)
    matrix = turn.as_matrix()
    np.testing.assert_allclose(turned, matrix @ cov @ matrix.T, rtol=1e-9, atol=1e-9 * np.max(cov))
    # Narrow field about +z: the roll axis (camera z) is the weak one.
    assert cov[2, 2] > 50 * max(cov[0, 0], cov[1, 1])


def test_batched_covariance_and_degenerate_geometry():
    rng = np.random.default_rng(31)
    observed = random_unit_vectors((3, 4), rng)
    observed[1] = observed[1, 0]  # all parallel: no roll information
    cov = attitude_covariance(observed, 1e-4)
    assert cov.shape == (3, 3, 3)
    assert np.all(np.isnan(cov[1])) and np.all(np.isfinite(cov[[0, 2]]))
    np.testing.assert_allclose(cov[2], attitude_covariance(observed[2], [1e-4] * 4), rtol=1e-12)


@pytest.mark.parametrize("sigma", [0.0, -1e-5, np.nan, [1e-5, 1e-5]])
def test_bad_sigma_raises(sigma):
    with pytest.raises(InvalidInputError, match="sigma_rad"):
        attitude_covariance(np.eye(3), sigma)


@pytest.fixture(scope="module")
def star_fields():
    """2000 star-tracker problems: 8 stars in a 12-degree field, 2-20 arcsec per star."""
    rng = np.random.default_rng(32)
    truth = Rotation.random(TRIALS, random_state=rng)  # rot_cam_from_icrs
    camera = cone_vectors((TRIALS, STARS), 6 * DEG, rng)
    sigma = rng.uniform(2, 20, size=(TRIALS, STARS)) * ARCSEC
    observed = perturb(camera, sigma, rng)
    catalog = np.einsum("mji,mnj->mni", truth.as_matrix(), camera)  # truth^-1 applied
    return truth, observed, sigma, catalog


@pytest.fixture(scope="module")
def campaign(star_fields):
    truth, observed, sigma, catalog = star_fields
    return truth, observed, sigma, solve_wahba(observed, catalog, sigma_rad=sigma)


def _nees(error, cov):
    return np.einsum("mi,mij,mj->m", error, np.linalg.inv(cov), error)


def test_solver_covariance_is_attitude_covariance(campaign):
    _, observed, sigma, result = campaign
    expected = attitude_covariance(observed, sigma)
    np.testing.assert_allclose(result.covariance_rad2, expected, rtol=1e-12)


def test_normalised_errors_are_chi_square_with_three_dof(campaign):
    truth, _, _, result = campaign
    error_cam = (truth * result.rotation.inv()).as_rotvec()  # acts on camera-frame vectors
    nees = _nees(error_cam, result.covariance_rad2)
    assert nees.mean() == pytest.approx(3.0, abs=0.1)  # P / 4 (quaternion part) would give 12
    assert stats.kstest(nees, "chi2", args=(3,)).pvalue > 0.01
    inside = np.mean(nees < stats.chi2.ppf(0.95, 3))
    assert inside == pytest.approx(0.95, abs=0.015)


def test_covariance_is_not_in_the_reference_frame(campaign):
    # The same error expressed in ICRS axes does not fit P at all: P is a camera-frame matrix.
    truth, _, _, result = campaign
    error_icrs = truth.inv().apply((truth * result.rotation.inv()).as_rotvec())
    assert _nees(error_icrs, result.covariance_rad2).mean() > 30.0


def test_weighted_loss_is_half_a_chi_square(campaign):
    # With weights 1 / sigma^2 the loss is half a chi-square with 2N - 3 degrees of freedom.
    _, _, _, result = campaign
    assert np.mean(2.0 * result.loss) == pytest.approx(2 * STARS - 3, abs=0.35)


@pytest.mark.parametrize("method", METHODS)
def test_every_solver_is_consistent_with_its_covariance(method, star_fields):
    # Each solver's own covariance (QUEST model; SVD / FOAM closed forms; TRIAD's) fits its errors.
    truth, observed, sigma, catalog = star_fields
    result = solve_wahba(observed, catalog, sigma_rad=sigma, method=method)
    error_cam = (truth * result.rotation.inv()).as_rotvec()
    nees = _nees(error_cam, result.covariance_rad2)
    assert nees.mean() == pytest.approx(3.0, abs=0.15)
    assert stats.kstest(nees, "chi2", args=(3,)).pvalue > 0.01


def test_svd_and_foam_covariances_are_equal_and_near_quest():
    rng = np.random.default_rng(33)
    truth = Rotation.random(50, random_state=rng)
    camera = cone_vectors((50, 6), 8 * DEG, rng)
    sigma = rng.uniform(2, 20, size=(50, 6)) * ARCSEC
    catalog = np.einsum("mji,mnj->mni", truth.as_matrix(), camera)
    exact = {m: solve_wahba(camera, catalog, sigma_rad=sigma, method=m).covariance_rad2 for m in METHODS}
    np.testing.assert_allclose(exact["svd"], exact["foam"], rtol=1e-8, atol=0)
    np.testing.assert_allclose(exact["svd"], exact["quest"], rtol=1e-6)  # equal without noise
    noisy = perturb(camera, sigma, rng)
    svd = solve_wahba(noisy, catalog, sigma_rad=sigma, method="svd").covariance_rad2
    np.testing.assert_allclose(svd, attitude_covariance(noisy, sigma), rtol=1e-2)


def test_triad_covariance_closed_form_for_perpendicular_pair():
    # b1 = x, b2 = y: rotation about x known from b2 alone (s2), about y and z from b1 (s1).
    s1, s2 = 1 * ARCSEC, 3 * ARCSEC
    observed = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    result = solve_wahba(observed, observed, method="triad", sigma_rad=[s1, s2])
    np.testing.assert_allclose(result.covariance_rad2, np.diag([s2**2, s1**2, s1**2]), rtol=1e-12)


def test_roll_cross_boresight_split():
    cov = np.diag([4.0, 2.0, 9.0]) * ARCSEC**2
    roll, cross = roll_cross_boresight(cov)
    assert roll == pytest.approx(3 * ARCSEC) and cross == pytest.approx(np.sqrt(3.0) * ARCSEC)
    roll_x, _ = roll_cross_boresight(np.stack([cov, cov]), boresight=[2.0, 0, 0])
    np.testing.assert_allclose(roll_x, 2 * ARCSEC)
    with pytest.raises(InvalidInputError, match="boresight"):
        roll_cross_boresight(cov, boresight=[0.0, 0.0, 0.0])


def test_narrow_field_roll_is_weaker_by_focal_over_spread():
    # Huffman 2006 §7.2: roll sigma ~ centroid sigma / spread, cross-boresight ~ centroid sigma.
    rng = np.random.default_rng(34)
    observed = cone_vectors((20,), 5 * DEG, rng)
    roll, cross = roll_cross_boresight(attitude_covariance(observed, 5 * ARCSEC))
    spread = np.sqrt(np.mean(np.sum(observed[:, :2] ** 2, axis=1)))  # rms radius, rad
    assert cross == pytest.approx(5 * ARCSEC / np.sqrt(20), rel=0.05)
    assert roll == pytest.approx(5 * ARCSEC / np.sqrt(20) / spread, rel=0.15)
