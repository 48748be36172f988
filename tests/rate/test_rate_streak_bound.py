"""The Cramér-Rao bound of a streaked frame's rate (startrack.rate.rate_bound and
_streak_model.information_covariance) and the chance of meeting a rate target
(startrack.rate.target_chance)."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import chi

from startrack import Camera, Status
from startrack.rate import StreakSolution, rate_bound, target_chance
from startrack.rate._streak_model import MODEL_FLOOR_PX, Timing, fit_joint, information_covariance, predict
from startrack.units import DEG

CAMERA = Camera.from_fov(1024, 1024, 12.0)
TIMING = Timing(0.2, 0.0, 1024)
ROT = Rotation.from_euler("zyx", [30, -20, 50], degrees=True)
OMEGA = 4.0 * DEG * np.array([0.2, -0.3, 0.93]) / np.linalg.norm([0.2, -0.3, 0.93])
"""Mostly about the boresight: the roll-dominated case whose precision issue 19's target tests."""


def _stars(count: int, rng: np.random.Generator) -> np.ndarray:
    """ICRS vectors (count, 3) of stars spread over the middle 80 % of the image at mid-exposure."""
    x, y = rng.uniform(0.1, 0.9, (2, count)) * CAMERA.width
    return ROT.inv().apply(CAMERA.pixel_to_vector(x, y))


def test_the_bound_is_the_scatter_of_the_joint_fit_over_noise_draws():
    rng = np.random.default_rng(19)
    stars = _stars(8, rng)
    sigma_px = rng.uniform(0.05, 0.3, 8)
    cov = np.einsum("k,ij->kij", sigma_px**2, np.eye(6))
    truth = predict(CAMERA, ROT, OMEGA, np.zeros(3), stars, TIMING)
    spread = np.sqrt(sigma_px**2 + MODEL_FLOOR_PX**2)[:, None]  # the fit adds the floor to each sigma
    omegas = []
    for _ in range(150):
        measured = truth + rng.standard_normal(truth.shape) * spread
        fit = fit_joint(CAMERA, stars, measured, cov, ROT, OMEGA, TIMING, fit_focal=True, outlier_chi2=math.inf)
        omegas.append(fit.omega_rad_s)
    scatter = np.cov(np.array(omegas).T)
    bound = information_covariance(CAMERA, stars, cov, ROT, OMEGA, np.zeros(3), TIMING, fit_focal=True)[3:6, 3:6]
    # 150 draws: the trace of a sample covariance is known to about 12 % (1 sigma)
    assert np.trace(scatter) / np.trace(bound) == pytest.approx(1.0, abs=0.35)
    # and its roll part dominates here, as on the frames that miss the 1 % target
    assert bound[2, 2] > 0.5 * np.trace(bound)


def test_nuisance_parameters_only_widen_the_bound():
    rng = np.random.default_rng(3)
    stars = _stars(6, rng)
    cov = np.einsum("k,ij->kij", np.full(6, 0.1**2), np.eye(6))
    fixed = information_covariance(CAMERA, stars, cov, ROT, OMEGA, np.zeros(3), TIMING)[3:6, 3:6]
    focal = information_covariance(CAMERA, stars, cov, ROT, OMEGA, np.zeros(3), TIMING, fit_focal=True)[3:6, 3:6]
    assert np.all(np.linalg.eigvalsh(focal - fixed) > -1e-12 * np.trace(fixed))


def test_an_unsolved_frame_has_no_bound():
    assert np.all(np.isnan(rate_bound(StreakSolution(status=Status.NO_MATCH), CAMERA, ROT, OMEGA)))


@pytest.mark.parametrize("sigma_pct", [0.3, 0.58, 1.0])
def test_the_chance_of_an_isotropic_error_is_the_chi_distribution(sigma_pct):
    cov = np.eye(3) * (sigma_pct / 100 * np.linalg.norm(OMEGA)) ** 2
    expected = chi(3).cdf(1.0 / sigma_pct)  # within 1 %, any axis
    assert target_chance(cov, OMEGA, 0.01, math.pi) == pytest.approx(expected, abs=0.025)


def test_the_axis_condition_cuts_the_chance():
    cov = np.diag([1.0, 1.0, 0.0]) * (0.008 * np.linalg.norm([0.0, 0.0, 1.0])) ** 2
    omega = np.array([0.0, 0.0, 1.0])  # errors across the axis only: 0.8 % per axis tilts it 0.46 deg
    loose = target_chance(cov, omega, 0.05, math.pi)
    tight = target_chance(cov, omega, 0.05, math.radians(0.5))
    assert loose == 1.0
    assert tight == pytest.approx(1.0 - math.exp(-0.5 * (math.tan(math.radians(0.5)) / 0.008) ** 2), abs=0.025)


def test_a_nan_covariance_has_no_chance():
    assert math.isnan(target_chance(np.full((3, 3), np.nan), OMEGA, 0.01, 0.01))
