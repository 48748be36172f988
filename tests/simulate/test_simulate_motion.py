"""Attitude kinematics and profiles, streak rendering and its truth, rolling shutter, sequences."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.simulate import (
    ConstantRate,
    FrameTiming,
    NoiseModel,
    RecordedProfile,
    Slew,
    VaryingRate,
    frame_rng,
    load_profile,
    random_attitude,
    render_gaussian_psf,
    render_stars,
    save_profile,
    simulate_frame,
    simulate_sequence,
    tumble,
)
from startrack.simulate._motion import quaternion_rate
from startrack.units import ARCSEC, DEG, PIXEL

EXPECTED_ONLY = NoiseModel(shot=False, dark=False, read=False, bias=False, quantize=False, saturate=False,
                           background=False)


def skew(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


# ---------------------------------------------------------------- kinematics
def test_constant_rate_obeys_the_attitude_kinematics():
    """dA/dt = -[omega x] A, and the quaternion rate of motion.py is its derivative."""
    w = np.array([0.3, -0.2, 0.5])
    profile = ConstantRate(random_attitude(1), w, t_ref_s=0.4)
    h = 1e-6
    a_minus, a_0, a_plus = profile.attitudes([0.7 - h, 0.7, 0.7 + h]).as_matrix()
    np.testing.assert_allclose((a_plus - a_minus) / (2 * h), -skew(w) @ a_0, atol=1e-8)
    q_minus, q_0, q_plus = profile.attitudes([0.7 - h, 0.7, 0.7 + h]).as_quat()
    if np.dot(q_plus, q_0) < 0:
        q_plus = -q_plus
    if np.dot(q_minus, q_0) < 0:
        q_minus = -q_minus
    np.testing.assert_allclose((q_plus - q_minus) / (2 * h), quaternion_rate(q_0, w), atol=1e-8)
    assert profile.attitudes([0.4])[0].approx_equal(profile.rot_ref, atol=1e-15)


def test_a_fixed_star_moves_opposite_to_the_camera_rotation():
    profile = ConstantRate(Rotation.identity(), [0.0, 0.01, 0.0])  # turning about +y
    v = profile.attitudes([1.0]).apply([0.0, 0.0, 1.0])[0]
    assert v[0] < 0 and abs(v[1]) < 1e-15  # the star drifts towards -x


def test_varying_rate_with_a_constant_rate_is_the_constant_rate_profile():
    w = np.array([0.02, 0.5, -0.1])
    rot = random_attitude(2)
    varying = VaryingRate(rot, lambda t: np.tile(w, (len(t), 1)), t_ref_s=1.0)
    exact = ConstantRate(rot, w, t_ref_s=1.0)
    times = [-2.0, 0.3, 1.0, 1.7, 4.0]
    err = (varying.attitudes(times) * exact.attitudes(times).inv()).magnitude()
    assert err.max() < 1e-3 * ARCSEC


def test_constant_angular_acceleration_about_a_fixed_axis_matches_the_closed_form():
    axis = np.array([1.0, 2.0, -2.0]) / 3.0
    w0, alpha = 0.3, 0.05  # rad/s, rad/s^2
    rot = random_attitude(3)
    profile = VaryingRate.accelerating(rot, w0 * axis, alpha * axis)
    t = np.array([0.5, 2.0, 6.0])
    angle = w0 * t + 0.5 * alpha * t * t
    exact = Rotation.from_rotvec(-angle[:, None] * axis) * rot
    assert (profile.attitudes(t) * exact.inv()).magnitude().max() < 1e-3 * ARCSEC
    np.testing.assert_allclose(profile.rates(t), (w0 + alpha * t)[:, None] * axis)


def test_slew_holds_turns_at_constant_rate_and_holds():
    a, b = random_attitude(4), random_attitude(5)
    slew = Slew(a, b, t_start_s=1.0, duration_s=10.0)
    start, end, before, after = slew.attitudes([1.0, 11.0, 0.0, 20.0])
    assert start.approx_equal(a, atol=1e-12) and before.approx_equal(a, atol=1e-12)
    assert end.approx_equal(b, atol=1e-12) and after.approx_equal(b, atol=1e-12)
    rates = slew.rates([0.5, 3.0, 9.0, 12.0])
    np.testing.assert_allclose(rates[1], rates[2])
    assert not rates[0].any() and not rates[3].any()
    assert np.linalg.norm(rates[1]) * 10.0 == pytest.approx((b * a.inv()).magnitude())


def test_recorded_profile_reproduces_a_constant_rate_and_survives_a_file(tmp_path):
    truth = tumble(random_attitude(6), [0.2, -1.0, 0.4], 3.0 * DEG)
    times = np.linspace(0.0, 10.0, 21)
    path = save_profile(tmp_path / "profile.csv", truth, times)
    profile = load_profile(path)
    t = np.array([0.1, 3.33, 9.9])
    assert (profile.attitudes(t) * truth.attitudes(t).inv()).magnitude().max() < 1e-6 * ARCSEC
    np.testing.assert_allclose(profile.rates(t), truth.rates(t), atol=1e-9)
    assert not profile.rates([11.0]).any()  # held after the record


@pytest.mark.parametrize("text", ["t_s,qx,qy,qz\n0,0,0,0\n", "t_s,qx,qy,qz,qw\n0,0,0,0,one\n1,0,0,0,1\n",
                                  "t_s,qx,qy,qz,qw\n1,0,0,0,1\n0,0,0,0,1\n"])
def test_bad_profile_files_are_refused(tmp_path, text):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InvalidInputError):
        load_profile(path)
    with pytest.raises(InvalidInputError):
        RecordedProfile([0.0], Rotation.identity(1))


# ---------------------------------------------------------------- streaks and their truth
@pytest.fixture
def camera() -> Camera:
    return Camera.from_fov(200, 160, 8.0)


def stars_at(camera, rot, x, y):
    return rot.inv().apply(camera.pixel_to_vector(np.asarray(x, float), np.asarray(y, float)))


def test_streak_end_points_in_the_truth_match_the_kinematics(camera, plain_sensor):
    """Rotation about +y moves a star at the principal point along x by f tan(omega t); about the
    boresight, a star moves on a circle: both in closed form, to 0.05 px."""
    rot = random_attitude(7)
    half_t = plain_sensor.exposure_s / 2
    w = 0.6 * DEG
    sim = render_stars(camera, rot, stars_at(camera, rot, [camera.cx], [camera.cy]), [3.0], [1],
                       sensor=plain_sensor, noise=False, rate_rad_s=(0.0, w, 0.0))
    t = sim.truth
    assert t.x_start[0] - camera.cx == pytest.approx(camera.fx * np.tan(w * half_t), abs=0.05 * PIXEL)
    assert t.x_end[0] - camera.cx == pytest.approx(-camera.fx * np.tan(w * half_t), abs=0.05 * PIXEL)
    assert abs(t.y_start[0] - camera.cy) < 1e-9 and abs(t.x[0] - camera.cx) < 1e-9
    radius = 60.0
    sim = render_stars(camera, rot, stars_at(camera, rot, [camera.cx + radius], [camera.cy]), [3.0], [1],
                       sensor=plain_sensor, noise=False, rate_rad_s=(0.0, 0.0, 5 * DEG))
    t, angle = sim.truth, 5 * DEG * half_t
    assert t.x_end[0] - camera.cx == pytest.approx(radius * np.cos(angle), abs=0.05 * PIXEL)
    assert t.y_end[0] - camera.cy == pytest.approx(-radius * np.sin(angle), abs=0.05 * PIXEL)
    assert t.y_start[0] - camera.cy == pytest.approx(radius * np.sin(angle), abs=0.05 * PIXEL)
    assert sim.truth.rate_cam_rad_s[2] == 5 * DEG
    assert (sim.truth.rot_start * sim.truth.rot_end.inv()).magnitude() == pytest.approx(2 * angle)


def test_streak_image_has_the_flux_centroid_and_length_of_its_truth(camera, plain_sensor):
    rot = random_attitude(8)
    sim = render_stars(camera, rot, stars_at(camera, rot, [100.3], [80.6]), [2.0], [1], sensor=plain_sensor,
                       noise=EXPECTED_ONLY, rate_rad_s=(0.0, 0.8 * DEG, 0.0))
    image = sim.image * plain_sensor.detector.gain_e_per_adu
    t = sim.truth
    length = float(t.streak_length_px[0])
    assert 15 < length < 25  # 0.8 deg/s for 1 s at 1430 px/rad
    assert image.sum() == pytest.approx(t.electrons[0], rel=1e-6)  # conserved (but the >5 sigma tails)
    rows, cols = np.indices(image.shape)
    total = image.sum()
    xc, yc = (cols * image).sum() / total, (rows * image).sum() / total
    assert xc == pytest.approx((t.x_start[0] + t.x_end[0]) / 2, abs=0.02 * PIXEL)
    assert yc == pytest.approx(t.y[0], abs=0.02 * PIXEL)
    var_x = ((cols - xc) ** 2 * image).sum() / total
    sigma = plain_sensor.psf_sigma_px
    assert np.sqrt(12 * (var_x - sigma**2 - 1 / 12)) == pytest.approx(length, rel=0.01)
    profile = image[round(yc), round(t.x_end[0]) + 8:round(t.x_start[0]) - 8]
    assert profile.max() / profile.min() - 1 < 1e-4  # no gaps, no ripple along the streak


def test_zero_rate_reduces_to_the_point_star_image(camera, plain_sensor):
    rot = random_attitude(9)
    v = stars_at(camera, rot, [30.2, 120.7, 180.0], [40.4, 90.1, 150.9])
    still = render_stars(camera, rot, v, [2.0, 3.0, 4.0], [1, 2, 3], sensor=plain_sensor, rng=3)
    zero = render_stars(camera, rot, v, [2.0, 3.0, 4.0], [1, 2, 3], sensor=plain_sensor, rng=3,
                        rate_rad_s=(0.0, 0.0, 0.0))
    held = render_stars(camera, ConstantRate(rot), v, [2.0, 3.0, 4.0], [1, 2, 3], sensor=plain_sensor, rng=3)
    np.testing.assert_array_equal(zero.image, still.image)
    np.testing.assert_array_equal(held.image, still.image)
    expected = render_stars(camera, rot, v, [2.0, 3.0, 4.0], [1, 2, 3], sensor=plain_sensor,
                            noise=EXPECTED_ONLY).image * plain_sensor.detector.gain_e_per_adu
    t = still.truth
    reference = render_gaussian_psf(expected.shape, t.x, t.y, t.electrons, plain_sensor.psf_sigma_px)
    np.testing.assert_allclose(expected, reference, rtol=1e-12, atol=1e-12)


def test_a_tiny_rate_is_a_slightly_longer_point(camera, plain_sensor):
    rot = random_attitude(10)
    v = stars_at(camera, rot, [77.7], [66.6])
    still = render_stars(camera, rot, v, [2.0], [1], sensor=plain_sensor, noise=EXPECTED_ONLY).image
    slow = render_stars(camera, rot, v, [2.0], [1], sensor=plain_sensor, noise=EXPECTED_ONLY,
                        rate_rad_s=(1e-3 * ARCSEC, 0.0, 0.0)).image
    np.testing.assert_allclose(slow, still, atol=1e-9 * still.max())


def test_rolling_shutter_shifts_each_row_by_the_motion_during_the_readout(camera, plain_sensor):
    """Stars in one column, the camera turning about +y: with a rolling shutter each star is caught
    ``y * line_time`` later, so it sits ``speed * y * line_time`` further along -x."""
    rot = random_attitude(11)
    ys = np.array([20.0, 80.0, 140.0])
    v = stars_at(camera, rot, np.full(3, 100.0), ys)
    w, line = 0.3 * DEG, 2e-4
    timing = FrameTiming(start_s=0.0, line_time_s=line)
    glob = render_stars(camera, rot, v, [2.0] * 3, [1, 2, 3], sensor=plain_sensor, noise=EXPECTED_ONLY,
                        rate_rad_s=(0.0, w, 0.0), timing=FrameTiming(start_s=0.0))
    roll = render_stars(camera, rot, v, [2.0] * 3, [1, 2, 3], sensor=plain_sensor, noise=EXPECTED_ONLY,
                        rate_rad_s=(0.0, w, 0.0), timing=timing)
    speed = camera.fx * w  # px/s near the axis
    shift = roll.truth.x - glob.truth.x
    np.testing.assert_allclose(shift, -speed * roll.truth.y * line, atol=0.05 * PIXEL)
    image = roll.image * plain_sensor.detector.gain_e_per_adu
    for x, y in zip(roll.truth.x, roll.truth.y, strict=True):
        patch = image[round(y) - 6:round(y) + 7, :]
        cols = np.arange(image.shape[1])
        assert (patch.sum(axis=0) * cols).sum() / patch.sum() == pytest.approx(x, abs=0.05 * PIXEL)
    assert image.sum() == pytest.approx(roll.truth.electrons.sum(), rel=1e-6)


def test_a_still_scene_is_the_same_with_a_rolling_shutter(camera, plain_sensor):
    rot = random_attitude(12)
    v = stars_at(camera, rot, [50.5, 150.2], [30.3, 120.8])
    a = render_stars(camera, rot, v, [2.0, 2.5], [1, 2], sensor=plain_sensor, noise=EXPECTED_ONLY)
    b = render_stars(camera, rot, v, [2.0, 2.5], [1, 2], sensor=plain_sensor, noise=EXPECTED_ONLY,
                     timing=FrameTiming(line_time_s=1e-4))
    np.testing.assert_allclose(a.image, b.image, atol=1e-9)


# ---------------------------------------------------------------- sequences
def test_sequence_frames_are_tagged_and_reproducible_one_by_one():
    camera = Camera.from_fov(96, 96, 10.0)
    profile = tumble(random_attitude(13), [0.3, 0.4, 1.0], 2.0 * DEG)
    frames = list(simulate_sequence(camera, profile, 3, frame_rate_hz=4.0, seed=99, max_mag=7.0))
    for k, sim in enumerate(frames):
        t_mid = k / 4.0 + frames[0].truth.exposure_s / 2
        assert sim.truth.frame_index == k and sim.truth.t_mid_s == pytest.approx(t_mid)
        assert (sim.truth.rot_cam_from_icrs * profile.attitudes([t_mid])[0].inv()).magnitude() < 1e-12
    alone = simulate_frame(camera, profile, max_mag=7.0, rng=frame_rng(99, 2), timing=FrameTiming(start_s=0.5))
    np.testing.assert_array_equal(alone.image, frames[2].image)
    assert not np.array_equal(frames[0].image, frames[1].image)


def test_sequence_refuses_an_exposure_longer_than_the_frame_period():
    with pytest.raises(InvalidInputError, match="frame period"):
        next(simulate_sequence(Camera.from_fov(32, 32, 5.0), ConstantRate(random_attitude(1)), 2,
                               frame_rate_hz=100.0))


def test_a_varying_rate_frame_matches_the_constant_rate_frame_when_the_rate_is_constant(camera, plain_sensor):
    rot = random_attitude(14)
    v = stars_at(camera, rot, [60.0, 140.0], [50.0, 110.0])
    w = np.array([0.2, 0.5, 1.0]) * DEG
    constant = render_stars(camera, ConstantRate(rot, w), v, [2.0, 3.0], [1, 2], sensor=plain_sensor,
                            noise=EXPECTED_ONLY, timing=FrameTiming(start_s=-0.5))
    varying = render_stars(camera, VaryingRate.accelerating(rot, w, np.zeros(3)), v, [2.0, 3.0], [1, 2],
                           sensor=plain_sensor, noise=EXPECTED_ONLY, timing=FrameTiming(start_s=-0.5))
    np.testing.assert_allclose(varying.image, constant.image, atol=1e-9 * constant.image.max())
    np.testing.assert_allclose(varying.truth.x_end, constant.truth.x_end, atol=1e-6 * PIXEL)


def test_airy_streak_conserves_light_and_is_centred_on_its_path(camera, plain_sensor):
    import dataclasses

    sensor = dataclasses.replace(plain_sensor, optics=dataclasses.replace(plain_sensor.optics, psf="airy",
                                                                          airy_first_zero_px=1.5))
    rot = random_attitude(15)
    sim = render_stars(camera, rot, stars_at(camera, rot, [100.0], [80.0]), [2.0], [1], sensor=sensor,
                       noise=EXPECTED_ONLY, rate_rad_s=(0.0, 0.4 * DEG, 0.0))
    image, t = sim.image * sensor.detector.gain_e_per_adu, sim.truth
    assert 0.93 < image.sum() / t.electrons[0] < 1.0
    cols = np.arange(image.shape[1])
    assert (image.sum(axis=0) * cols).sum() / image.sum() == pytest.approx((t.x_start[0] + t.x_end[0]) / 2,
                                                                          abs=0.05 * PIXEL)


def test_same_seed_same_streaked_frame_with_every_effect(camera):
    import dataclasses

    from startrack.simulate import SkyBackground, get_sensor_preset

    base = get_sensor_preset("generic-cmos")
    sensor = dataclasses.replace(base, detector=dataclasses.replace(
        base.detector, prnu_rms=0.01, dsnu_rms=0.2, hot_pixel_fraction=1e-3, dead_pixel_fraction=1e-3))
    frames = [simulate_frame(camera, random_attitude(16), max_mag=8.0, sensor=sensor, rng=seed,
                             rate_rad_s=(0.3 * DEG, 0.1 * DEG, 0.5 * DEG), noise=NoiseModel(blooming=True),
                             sky_background=SkyBackground(mag_arcsec2=21.0, stray_e_s_px=4.0),
                             timing=FrameTiming(line_time_s=2e-5)).image for seed in (8, 8, 9)]
    np.testing.assert_array_equal(frames[0], frames[1])
    assert np.any(frames[0] != frames[2])
