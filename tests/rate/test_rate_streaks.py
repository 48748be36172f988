"""Streaked frames (Sease 2013 ch. 3-4): endpoints, grouping, catalog-free rate, RSO flags, mode."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from streak_scenes import render_streak_scene, spin_rate, star_field

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.rate import axis_error_rad
from startrack.rate._catalog_free import catalog_free_rate
from startrack.rate._endpoints import (
    DETECTORS,
    along_streak_offsets,
    calibrate_bias,
    gaussian_derivative_kernel,
    locate_endpoints,
)
from startrack.rate._grouping import centre_of_rotation, group_endpoints
from startrack.rate._streak_detect import find_streaks
from startrack.rate._streak_rate import attitudes_from_matches, choose_mode, measure_streaks, streak_rate
from startrack.results import Status
from startrack.units import DEG, PIXEL

SCENE_KEYS = [(45, 0.1), (90, 0.1), (45, 0.5), (90, 0.5)]
CAMERA = Camera.from_fov(1024, 1024, fov_deg=20.0)
FOV = 20 * DEG
RATE = 0.05  # rad/s
HARRIS_BIAS_PX = 0.64  # calibrated below (test_bias_calibration_...)


def _apart(camera, omega, exposure, vectors, gap_px=15.0):
    """True when no two star paths (sampled) come closer than ``gap_px``."""
    samples = []
    for t in np.linspace(0.0, exposure, 40):
        x, y = camera.vector_to_pixel(Rotation.from_rotvec(-omega * t).apply(vectors))
        samples.append(np.stack([x, y], axis=1))
    paths = np.stack(samples, axis=1)  # (N, 40, 2)
    for i in range(len(paths)):
        for j in range(i):
            if np.min(np.linalg.norm(paths[i][:, None] - paths[j][None], axis=2)) < gap_px:
                return False
    return True


def _scene(seed, theta_deg, fraction, stars=12, rso=False):
    rng = np.random.default_rng(seed)
    omega = spin_rate(theta_deg * DEG, RATE, rng.uniform(0, 2 * np.pi))
    exposure = fraction * FOV / RATE
    vectors = star_field(CAMERA, omega, exposure, stars + rso, rng, margin_px=15)
    while not _apart(CAMERA, omega, exposure, vectors):  # separate streaks: the seed's corrupted ROIs aside
        vectors = star_field(CAMERA, omega, exposure, stars + rso, rng, margin_px=15)
    flux = rng.uniform(1e5, 5e5, stars + rso) * fraction / 0.1
    own = np.zeros((stars + rso, 3))
    if rso:  # its own motion across the sky, 0.4 of the camera's rate
        side = np.cross(vectors[-1], rng.normal(size=3))
        own[-1] = 0.4 * RATE * side / np.linalg.norm(side)
    return render_streak_scene(CAMERA, Rotation.random(random_state=rng), omega, exposure, vectors, flux,
                               rso_omega_cam=own, rng=rng)


@pytest.fixture(scope="module")
def scenes():
    return {
        (theta, fraction): _scene(10 + theta, theta, fraction, stars=10 if fraction < 0.3 else 4)
        for theta in (45, 90)
        for fraction in (0.1, 0.5)
    }


def _match_truth(scene, ends):
    """The true (start, end) (N, 2, 2) of each measured streak, ordered like its ends."""
    truth_mid = 0.5 * (scene.start_xy + scene.end_xy)
    out = []
    for pair in ends:
        k = np.argmin(np.linalg.norm(truth_mid - pair.mean(axis=0), axis=1))
        true = np.stack([scene.start_xy[k], scene.end_xy[k]])
        out.append(true if np.linalg.norm(pair[0] - true[0]) < np.linalg.norm(pair[0] - true[1]) else true[::-1])
    return np.array(out)


def test_derivative_kernel_matches_the_seed():
    kernel = gaussian_derivative_kernel()
    np.testing.assert_allclose(np.abs(kernel[1]), [0.3446, 0, 0.3446], atol=5e-5)
    np.testing.assert_allclose(np.abs(kernel[0]), [0.0466, 0, 0.0466], atol=5e-5)


def test_every_detector_finds_both_ends_of_an_isolated_streak():
    scene = _scene(1, 90, 0.1, stars=1)
    field = find_streaks(scene.image)
    region = field.regions[0]
    roi = scene.image[region.rows, region.cols] - field.background
    truth = np.stack([scene.start_xy[0], scene.end_xy[0]])
    for detector in DETECTORS:
        ends = locate_endpoints(roi, region.origin_xy, detector)
        assert ends.ok, detector
        paired = _match_truth(scene, ends.xy[None])[0]
        assert np.max(np.linalg.norm(ends.xy - paired, axis=1)) < 2.5 * PIXEL  # biased inward
    assert truth.shape == (2, 2)


def test_bias_calibration_from_truth_and_from_moments_agree(scenes):
    scene = scenes[(90, 0.1)]
    field = find_streaks(scene.image)
    ends, lengths = [], []
    for region in field.regions:
        found = locate_endpoints(scene.image[region.rows, region.cols] - field.background, region.origin_xy)
        if found.ok:
            ends.append(found.xy)
            lengths.append(region.length_moments_px)
    ends = np.array(ends)
    from_truth = calibrate_bias(ends, _match_truth(scene, ends))
    from_moments = calibrate_bias(ends, length_moments_px=lengths)
    assert from_truth == pytest.approx(HARRIS_BIAS_PX, abs=0.15 * PIXEL)
    assert from_moments == pytest.approx(from_truth, abs=0.3 * PIXEL)
    with pytest.raises(InvalidInputError, match="reference_xy or length_moments_px"):
        calibrate_bias(ends)


@pytest.mark.parametrize("key", [(45, 0.1), (90, 0.1), (45, 0.5), (90, 0.5)])
def test_calibrated_harris_endpoints_are_within_a_fifth_of_a_pixel(scenes, key):
    scene = scenes[key]
    meas = measure_streaks(scene.image, CAMERA, detector="harris", bias_px=HARRIS_BIAS_PX)
    ends = np.stack([meas.ends_a, meas.ends_b], axis=1)
    errors = np.linalg.norm(ends - _match_truth(scene, ends), axis=2)
    assert np.sqrt(np.mean(errors**2)) < 0.2 * PIXEL
    offsets = along_streak_offsets(ends, _match_truth(scene, ends))
    assert abs(np.mean(offsets)) < 0.1 * PIXEL  # the calibration removed the inward bias


@pytest.mark.parametrize("key, detector, bias", [(key, "segment", 0.0) for key in SCENE_KEYS]
                         + [(key, "harris", HARRIS_BIAS_PX) for key in SCENE_KEYS])
def test_catalog_free_rate_within_one_percent_and_half_a_degree(scenes, key, detector, bias):
    # The requirement for streaks of 10 % of the FOV or longer.
    scene = scenes[key]
    result = streak_rate(scene.image, CAMERA, scene.exposure_s, detector=detector, bias_px=bias,
                         prior_omega_rad_s=scene.omega_rad_s)
    omega = result.rate.omega_rad_s
    assert result.rate.ok and result.time_order_known
    assert np.linalg.norm(omega - scene.omega_rad_s) < 0.01 * RATE
    assert axis_error_rad(omega, scene.omega_rad_s) < 0.5 * DEG
    assert len(result.rso.candidates) == 0  # stars only: nothing flagged


def test_two_streaks_give_no_checked_rate():
    # 2 streaks fix a rotation but nothing checks it, so no rate is claimed.
    scene = _scene(12, 45, 0.5, stars=2)
    result = streak_rate(scene.image, CAMERA, scene.exposure_s, detector="harris", bias_px=HARRIS_BIAS_PX)
    assert len(result.measurement.regions) == 2
    assert result.rate.status is Status.TOO_FEW_STARS and "agree" in result.rate.reason


def test_groups_are_the_two_exposure_ends(scenes):
    scene = scenes[(45, 0.1)]
    meas = measure_streaks(scene.image, CAMERA, detector="harris", bias_px=HARRIS_BIAS_PX)
    start_first = [np.linalg.norm(a - scene.start_xy, axis=1).min() < 1.0 for a in meas.ends_a]
    assert all(start_first) or not any(start_first)  # one group is all starts, the other all ends


def test_attitudes_at_both_ends_from_identified_streaks(scenes):
    # Sease 2013 ch. 3: the same identified stars at both ends give the attitude at both times.
    scene = scenes[(90, 0.5)]
    meas = measure_streaks(scene.image, CAMERA, detector="harris", bias_px=HARRIS_BIAS_PX)
    mids = 0.5 * (scene.start_xy + scene.end_xy)
    centres = 0.5 * (meas.ends_a + meas.ends_b)
    stars = [np.argmin(np.linalg.norm(mids - c, axis=1)) for c in centres]
    a_is_start = np.linalg.norm(meas.ends_a[0] - scene.start_xy[stars[0]]) < 1.0
    starts, ends = (meas.ends_a, meas.ends_b) if a_is_start else (meas.ends_b, meas.ends_a)
    rot_start, rot_end = attitudes_from_matches(CAMERA.pixel_to_vector(*starts.T), CAMERA.pixel_to_vector(*ends.T),
                                                scene.icrs[stars])
    pixel = 1.0 / CAMERA.fx
    assert (scene.rot_start * rot_start.inv()).magnitude() < 0.5 * pixel  # few stars: roll-limited
    assert (scene.rot_end * rot_end.inv()).magnitude() < 0.5 * pixel


def test_rso_is_flagged_and_no_star_is():
    scene = _scene(7, 60, 0.15, stars=10, rso=True)
    result = streak_rate(scene.image, CAMERA, scene.exposure_s, detector="harris", bias_px=HARRIS_BIAS_PX,
                         prior_omega_rad_s=scene.omega_rad_s)
    mids = 0.5 * (result.measurement.ends_a + result.measurement.ends_b)
    rso_index = np.argmin(np.linalg.norm(mids - 0.5 * (scene.start_xy[-1] + scene.end_xy[-1]), axis=1))
    np.testing.assert_array_equal(result.rso.candidates, [rso_index])
    assert not result.rate.used[rso_index]  # the rate was solved without it
    assert np.linalg.norm(result.rate.omega_rad_s - scene.omega_rad_s) < 0.01 * RATE


def test_parallel_streaks_use_the_direction_rule():
    first = np.array([[100.0, 100.0], [400.0, 300.0], [700.0, 800.0]])
    second = first + [50.0, 5.0]
    mixed = np.array([[1], [0], [1]], dtype=bool)  # ends handed over in mixed order
    p1, p2 = np.where(mixed, first, second), np.where(mixed, second, first)
    cor = centre_of_rotation(p1, p2)
    assert cor.parallel and np.all(np.isnan(cor.residual_px))
    a, b, _ = group_endpoints(p1, p2, cor)
    motion = b - a
    np.testing.assert_allclose(np.abs(motion), np.tile([50.0, 5.0], (3, 1)))
    np.testing.assert_allclose(motion, np.tile(motion[0], (3, 1)))  # one group is one time


def test_circular_streaks_find_their_centre():
    centre = np.array([300.0, 200.0])
    angles = np.array([0.3, 1.5, 2.8, 4.0])
    radii = np.array([100.0, 150.0, 220.0, 90.0])
    first = centre + radii[:, None] * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    second = centre + radii[:, None] * np.stack([np.cos(angles + 0.2), np.sin(angles + 0.2)], axis=1)
    mixed = np.array([[1], [0], [1], [0]], dtype=bool)
    p1, p2 = np.where(mixed, first, second), np.where(mixed, second, first)
    cor = centre_of_rotation(p1, p2)
    np.testing.assert_allclose(cor.xy, centre, atol=1e-9)
    np.testing.assert_allclose(cor.residual_px, 0.0, atol=1e-9)
    a, _, _ = group_endpoints(p1, p2, cor)
    assert np.allclose(a, first) or np.allclose(a, second)


def test_catalog_free_rate_misuse_and_too_few():
    with pytest.raises(InvalidInputError, match="exposure_s"):
        catalog_free_rate(np.eye(3), np.eye(3), 0.0)
    assert catalog_free_rate(np.eye(3)[:1], np.eye(3)[:1], 1.0).estimate.status is Status.TOO_FEW_STARS


def test_mode_switches_between_point_and_streak():
    point_like = _scene(3, 90, 0.005, stars=8)
    assert choose_mode(point_like.image).mode == "point"
    assert choose_mode(_scene(4, 90, 0.2, stars=8).image).mode == "streak"
