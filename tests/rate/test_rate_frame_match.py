"""Matching the stars of two unidentified frames, and the rate only when the pairs support it."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.attitude import propagate
from startrack.errors import InvalidInputError
from startrack.frames import normalize
from startrack.rate import match_frames, rate_from_frames
from startrack.results import Status
from startrack.units import ARCSEC, DEG

OMEGA = np.array([3.0, -2.0, 1.5]) * DEG  # rad/s, camera frame: 2 deg of motion in DT
DT = 0.5  # s
SIGMA = 10 * ARCSEC  # centroid noise of one star in one frame, per axis


def _field(rng, n, half_angle=6 * DEG):
    xy = rng.uniform(-np.tan(half_angle), np.tan(half_angle), size=(n, 2))
    return normalize(np.column_stack([xy, np.ones(n)]))


def _pair(seed, n=20, sigma=SIGMA):
    """Frame a, frame b (shuffled, noisy) and the order: b[k] is star order[k] of a."""
    rng = np.random.default_rng(seed)
    a = _field(rng, n)
    order = rng.permutation(n)
    b = propagate(Rotation.identity(), OMEGA, DT).apply(a)[order]
    return (normalize(a + rng.normal(scale=sigma, size=a.shape)),
            normalize(b + rng.normal(scale=sigma, size=b.shape)), order)


@pytest.mark.parametrize("seed", range(4))
def test_stars_moving_most_of_their_spacing_are_all_matched(seed):
    # 20 stars over 12 x 12 deg (spacing ~2.7 deg) moving 2 deg: nearest neighbours are mostly
    # other stars, which the old nearest-neighbour rounds paired (0-3 pairs, some wrong)
    a, b, order = _pair(seed)
    pairs = match_frames(a, b, 3 * DEG, tol_rad=6 * SIGMA)
    assert len(pairs) == 20
    np.testing.assert_array_equal(order[pairs[:, 1]], pairs[:, 0])


def test_the_rate_is_within_its_uncertainty():
    nees = []
    for seed in range(40):
        a, b, _ = _pair(100 + seed)
        found = rate_from_frames(a, b, DT, max_angle_rad=3 * DEG, sigma_rad=SIGMA)
        assert found.estimate.ok and len(found.pairs) == 20
        error = found.estimate.omega_rad_s - OMEGA
        nees.append(error @ np.linalg.inv(found.estimate.covariance_rad2_s2) @ error)
        assert found.residual_rms_rad < 4 * SIGMA  # the pair difference has sqrt(2) SIGMA per axis
    assert np.mean(nees) == pytest.approx(3.0, abs=0.9)  # chi-square, 3 dof, 40 trials


def test_too_few_stars_are_not_a_rate():
    a, b, _ = _pair(7, n=3)
    found = rate_from_frames(a, b, DT, max_angle_rad=3 * DEG, sigma_rad=SIGMA)
    assert found.estimate.status is Status.TOO_FEW_STARS and "4" in found.estimate.reason
    assert np.all(np.isnan(found.estimate.omega_rad_s))


def test_pairs_that_do_not_fit_one_rotation_within_the_noise_are_not_a_rate():
    a, b, _ = _pair(8, sigma=5 * SIGMA)  # five times the centroid error the caller states
    found = rate_from_frames(a, b, DT, max_angle_rad=3 * DEG, sigma_rad=SIGMA / 2, min_pairs=4)
    assert found.estimate.status in (Status.DEGENERATE, Status.TOO_FEW_STARS)
    assert not found.estimate.ok


def test_no_match_says_to_raise_the_motion_gate():
    a, b, _ = _pair(9)
    found = rate_from_frames(a, b, DT, max_angle_rad=0.5 * DEG, sigma_rad=SIGMA)  # the stars move 2 deg
    assert found.estimate.status is Status.NO_MATCH
    assert "no stars matched" in found.estimate.reason and "max_angle_rad" in found.estimate.reason
    assert "non-parallel" not in found.estimate.reason


@pytest.mark.parametrize(("change", "match"), [
    ({"vectors_a": np.full((5, 3), np.nan)}, "finite"),
    ({"vectors_a": np.ones((5, 2))}, r"\(N, 3\)"),
    ({"max_angle_rad": 0.0}, "max_angle_rad"),
    ({"max_angle_rad": np.nan}, "max_angle_rad"),
    ({"tol_rad": 1.0}, "tol_rad"),  # larger than the motion gate
    ({"predicted": "identity"}, "predicted"),
])
def test_match_frames_refuses_bad_input(change, match):
    a, b, _ = _pair(10)
    kwargs = {"vectors_a": a, "vectors_b": b, "max_angle_rad": 3 * DEG} | change
    with pytest.raises(InvalidInputError, match=match):
        match_frames(**kwargs)


@pytest.mark.parametrize(("change", "match"), [
    ({"dt_s": 0.0}, "dt_s"),
    ({"dt_s": np.nan}, "dt_s"),
    ({"sigma_rad": -1.0}, "sigma_rad"),
    ({"sigma_rad": np.inf}, "sigma_rad"),
    ({"min_pairs": 1}, "min_pairs"),
])
def test_rate_from_frames_refuses_bad_input(change, match):
    a, b, _ = _pair(11)
    kwargs = {"dt_s": DT, "max_angle_rad": 3 * DEG, "sigma_rad": SIGMA} | change
    with pytest.raises(InvalidInputError, match=match):
        rate_from_frames(a, b, **kwargs)
