"""The predicted streaks of a frame's other stars are fitted only while the identified streaks
leave the rate uncertain (StreakOptions.enough_rate_uncertainty): a frame of long streaks skips
them, and what it reports is still right within its claimed uncertainty."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.rate import StreakOptions, solve_streaked
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import DEG

CAMERA = Camera.from_fov(1024, 1024, 20.0)
OMEGA = 1.0 * DEG * np.array([0.2, 0.5, -0.8]) / np.linalg.norm([0.2, 0.5, -0.8])
EXPOSURE_S = 2.0  # streaks of about 100 px, 10 % of the field


@pytest.fixture(scope="module")
def solutions():
    sensor = get_sensor_preset("generic-cmos").with_exposure(EXPOSURE_S)
    sim = simulate_frame(CAMERA, Rotation.from_euler("zyx", [120, -35, 60], degrees=True), max_mag=7.5,
                         epoch_jyear=2025.0, sensor=sensor, rng=3, rate_rad_s=OMEGA)

    def solve(enough):
        return solve_streaked(sim.image, fov_deg=20.0, exposure_s=EXPOSURE_S, epoch=2025.0, prior_omega_rad_s=OMEGA,
                              options=StreakOptions(enough_rate_uncertainty=enough))

    out = {"always": solve(0.0), "never": solve(1.0)}
    identified = _sigma3(out["never"])  # what the identified streaks alone leave (measured 0.56 %)
    out.update(above=solve(1.01 * identified), below=solve(0.99 * identified))
    return out


def _sigma3(solution) -> float:
    """3-sigma of the rate vector over the rate."""
    return 3.0 * math.sqrt(float(np.trace(solution.rate.covariance_rad2_s2))) / float(np.linalg.norm(OMEGA))


def test_fitting_the_predicted_streaks_adds_streaks_and_precision(solutions):
    always, never = solutions["always"], solutions["never"]
    assert always.solved and never.solved
    assert always.n_streaks > never.n_streaks  # measured 29 and 7
    assert _sigma3(always) < _sigma3(never)


def test_they_are_skipped_exactly_when_the_identified_streaks_suffice(solutions):
    assert solutions["above"].n_streaks == solutions["never"].n_streaks
    assert solutions["below"].n_streaks == solutions["always"].n_streaks


@pytest.mark.parametrize("which", ["always", "never"])
def test_each_rate_is_right_within_its_claimed_uncertainty(solutions, which):
    solution = solutions[which]
    assert solution.rate.ok, solution.rate.reason
    error = np.linalg.norm(solution.turn_rad / EXPOSURE_S - OMEGA)
    assert error < 3.0 * math.sqrt(float(np.trace(solution.rate.covariance_rad2_s2)))  # rad/s, 3 sigma


@pytest.mark.parametrize(("streaks", "birge", "sigma3", "enough"),
                         [(5, 1.0, 0.004, True), (4, 1.0, 0.004, False), (5, 3.5, 0.004, False),
                          (5, 1.0, 0.006, False)])
def test_only_enough_streaks_that_fit_one_rotation_stop_the_predicted_stage(streaks, birge, sigma3, enough):
    from startrack.rate._streak_model import JointFit
    from startrack.rate._streak_solve import _known_enough

    covariance = np.zeros((10, 10))
    covariance[3:6, 3:6] = np.eye(3) * (sigma3 * np.linalg.norm(OMEGA) / 3.0) ** 2 / 3.0  # (rad/s)^2
    joint = JointFit(Rotation.identity(), OMEGA, np.zeros(3), covariance, np.ones(streaks, dtype=bool),
                     np.zeros(streaks), birge, np.zeros((streaks, 6)), np.zeros((streaks, 6)), CAMERA)
    assert _known_enough(joint, StreakOptions()) is enough
