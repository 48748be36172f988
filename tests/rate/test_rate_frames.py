"""Rate from attitudes, from matched vectors between frames, and the filter over a sequence."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.attitude import propagate
from startrack.errors import InvalidInputError
from startrack.frames import normalize
from startrack.rate import (
    RateFilter,
    axis_error_rad,
    match_frames,
    rate_between,
    rate_from_attitudes,
    rate_from_vectors,
)
from startrack.results import Status
from startrack.units import ARCSEC, DEG

OMEGA = np.array([0.01, -0.03, 0.02])  # rad/s, camera frame


def _field(rng, n=15, half_angle=6 * DEG):
    xy = rng.uniform(-np.tan(half_angle), np.tan(half_angle), size=(n, 2))
    return normalize(np.column_stack([xy, np.ones(n)]))


def _noisy(rotations, sigma, rng):
    return Rotation.from_rotvec(rng.normal(scale=sigma, size=(len(rotations), 3))) * rotations


def test_exact_rate_between_two_attitudes_and_the_seed_first_order_form():
    start = Rotation.random(random_state=np.random.default_rng(60))
    later = propagate(start, OMEGA, 0.5)
    np.testing.assert_allclose(rate_between(start, later, 0.5), OMEGA, rtol=1e-12)
    first = rate_between(start, later, 0.5, first_order=True)  # Samaan 2002 eq. 3
    bias = np.linalg.norm(first - OMEGA) / np.linalg.norm(OMEGA)
    assert 0 < bias < (np.linalg.norm(OMEGA) * 0.5) ** 2  # second order in the step angle
    np.testing.assert_allclose(rate_between(later, start, -0.5), OMEGA, rtol=1e-12)


def test_rate_from_many_noisy_attitudes_is_consistent_with_its_covariance():
    rng = np.random.default_rng(61)
    times = np.arange(11) * 0.2
    sigma = 5 * ARCSEC
    truth = propagate(Rotation.random(random_state=rng), OMEGA, times)
    errors, covs = [], []
    for _ in range(300):
        est = rate_from_attitudes(_noisy(truth, sigma, rng), times, np.tile(np.eye(3) * sigma**2, (11, 1, 1)))
        errors.append(est.omega_rad_s - OMEGA)
        covs.append(est.covariance_rad2_s2)
    errors = np.array(errors)
    nees = np.einsum("mi,mij,mj->m", errors, np.linalg.inv(np.array(covs)), errors)
    assert nees.mean() == pytest.approx(3.0, abs=0.4)
    pair = rate_from_attitudes(truth[[0, 1]], times[:2], np.tile(np.eye(3) * sigma**2, (2, 1, 1)))
    np.testing.assert_allclose(np.diag(pair.covariance_rad2_s2), 2 * sigma**2 / 0.2**2, rtol=1e-9)
    scatter_only = rate_from_attitudes(_noisy(truth, sigma, rng), times)
    assert scatter_only.ok and np.all(scatter_only.sigma_rad_s < 5 * sigma / 2.0)


def test_rate_from_attitudes_failures_and_misuse():
    rot = Rotation.random(3, random_state=np.random.default_rng(62))
    assert rate_from_attitudes(rot[:1], [0.0]).status is Status.TOO_FEW_STARS
    with pytest.raises(InvalidInputError, match="increasing"):
        rate_from_attitudes(rot, [0.0, 0.0, 1.0])
    with pytest.raises(InvalidInputError, match="one time per rotation"):
        rate_from_attitudes(rot, [0.0, 1.0])


def test_rate_from_matched_vectors_without_catalog():
    rng = np.random.default_rng(63)
    dt, sigma = 0.25, 2 * ARCSEC
    a = _field(rng)
    b = propagate(Rotation.identity(), OMEGA, dt).apply(a)  # the same stars, camera turned
    est = rate_from_vectors(a, b, dt)
    np.testing.assert_allclose(est.omega_rad_s, OMEGA, rtol=1e-10)
    errors, covs = [], []
    for _ in range(300):
        noisy_a = normalize(a + rng.normal(scale=sigma / np.sqrt(2), size=a.shape))
        noisy_b = normalize(b + rng.normal(scale=sigma / np.sqrt(2), size=b.shape))
        fit = rate_from_vectors(noisy_a, noisy_b, dt, sigma_rad=sigma)  # sqrt(2 (sigma / sqrt 2)^2)
        errors.append(fit.omega_rad_s - OMEGA)
        covs.append(fit.covariance_rad2_s2)
    nees = np.einsum("mi,mij,mj->m", np.array(errors), np.linalg.inv(np.array(covs)), np.array(errors))
    assert nees.mean() == pytest.approx(3.0, abs=0.5)
    assert rate_from_vectors(a[:1], b[:1], dt).status is Status.DEGENERATE


def test_match_frames_recovers_the_permutation():
    rng = np.random.default_rng(64)
    a = _field(rng, n=40)
    turn = propagate(Rotation.identity(), OMEGA, 0.1)  # ~0.2 deg of motion
    order = rng.permutation(40)
    b = turn.apply(a)[order]
    b = np.vstack([b, _field(rng, n=3)])  # three stars only in frame b
    pairs = match_frames(a[:35], b, max_angle_rad=0.5 * DEG)
    assert len(pairs) == 35
    np.testing.assert_array_equal(order[pairs[:, 1]], pairs[:, 0])
    assert len(match_frames(a, np.zeros((0, 3)), 0.01)) == 0


def test_filter_tracks_a_constant_rate_better_than_frame_differences():
    rng = np.random.default_rng(65)
    times = np.arange(40) * 0.1
    sigma = 10 * ARCSEC
    truth = propagate(Rotation.random(random_state=rng), OMEGA, times)
    measured = _noisy(truth, sigma, rng)
    filt = RateFilter(rate_noise_rad_s2=1e-7)
    for rot, t in zip(measured, times, strict=True):
        state = filt.update_attitude(rot, t, sigma**2)
    rate = state.rate()
    difference = rate_between(measured[-2], measured[-1], 0.1)
    assert np.linalg.norm(rate.omega_rad_s - OMEGA) < 0.2 * np.linalg.norm(difference - OMEGA)
    assert np.all(np.abs(rate.omega_rad_s - OMEGA) < 4 * rate.sigma_rad_s)
    assert (truth[-1] * state.rotation.inv()).magnitude() < 3 * sigma
    assert axis_error_rad(rate.omega_rad_s, OMEGA) < 0.5 * DEG


def test_filter_takes_rate_measurements():
    filt = RateFilter()
    with pytest.raises(InvalidInputError, match="first attitude"):
        filt.update_rate(OMEGA, 0.0, 1e-6)
    filt.update_attitude(Rotation.identity(), 0.0, 1e-10)
    state = filt.update_rate(OMEGA, 0.0, 1e-8)
    np.testing.assert_allclose(state.omega_rad_s, OMEGA, rtol=1e-4)
    with pytest.raises(InvalidInputError, match="go back"):
        filt.update_attitude(Rotation.identity(), -1.0, 1e-10)
