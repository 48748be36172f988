"""QUEST covariance: closed forms, and a chi-square check of the frame and the factor of 4."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from scipy.spatial.transform import Rotation
from wahba_problems import cone_vectors, perturb, random_unit_vectors

from startrack.attitude import attitude_covariance, solve_wahba
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
def campaign():
    """2000 star-tracker problems: 8 stars in a 12-degree field, 2-20 arcsec per star."""
    rng = np.random.default_rng(32)
    truth = Rotation.random(TRIALS, random_state=rng)  # rot_cam_from_icrs
    camera = cone_vectors((TRIALS, STARS), 6 * DEG, rng)
    sigma = rng.uniform(2, 20, size=(TRIALS, STARS)) * ARCSEC
    observed = perturb(camera, sigma, rng)
    catalog = np.einsum("mji,mnj->mni", truth.as_matrix(), camera)  # truth^-1 applied
    result = solve_wahba(observed, catalog, sigma_rad=sigma)
    return truth, observed, sigma, result


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
