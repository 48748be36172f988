"""The Tracker through a slew that speeds up to 8 deg/s and back (issue 19): an attitude on every
frame, point mode at rest, streak mode at speed, and the switches between them."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.frames import attitude_error
from startrack.simulate import VaryingRate, get_sensor_preset, simulate_sequence
from startrack.track import Tracker
from startrack.track.tracker import POINT_MODE, STREAK_MODE
from startrack.units import DEG

CAMERA = Camera.from_fov(512, 512, 20.0)
EXPOSURE_S = 0.1
PEAK = 8.0 * DEG
AXIS = np.array([0.3, -0.9, 0.2]) / np.linalg.norm([0.3, -0.9, 0.2])


def slew_rate(t_s):
    """Rest 0.4 s, speed up to 8 deg/s in 1.6 s, hold 0.4 s, slow down in 1.6 s, rest (rad/s, (N, 3))."""
    t = np.asarray(t_s, dtype=float) - 0.4
    speed = PEAK * np.clip(np.minimum(t / 1.6, (3.6 - t) / 1.6), 0.0, 1.0)
    return speed[:, None] * AXIS[None, :]


@pytest.fixture(scope="module")
def run():
    profile = VaryingRate(Rotation.from_euler("zyx", [40, 20, 10], degrees=True), slew_rate)
    sensor = get_sensor_preset("generic-cmos").with_exposure(EXPOSURE_S)
    frames = simulate_sequence(CAMERA, profile, 12, frame_rate_hz=2.5, sensor=sensor, seed=3, max_mag=7.5,
                               catalog_epoch_jyear=2025.0)
    tracker = Tracker(width=512, height=512, fov_deg=20.0, epoch=2025.0)
    out = []
    for sim in frames:
        step = tracker.update_image(sim.image, sim.truth.t_mid_s, streak_exposure_s=EXPOSURE_S)
        speed = float(np.linalg.norm(slew_rate([sim.truth.t_mid_s])[0]))
        out.append((sim.truth, step, tracker.mode, speed))
    return out


def test_an_attitude_on_every_frame(run):
    pixel = CAMERA.pixel_scale_arcsec * np.pi / (180 * 3600)
    for truth, step, _, speed in run:
        assert step.status, f"no attitude at {speed / DEG:.1f} deg/s: {step.reason}"
        assert attitude_error(truth.rot_cam_from_icrs, step.rot_cam_from_icrs) < 2 * pixel  # 2 px of 141 arcsec


def test_point_mode_at_rest_streak_mode_at_speed_and_the_switches(run):
    modes = [mode for _, _, mode, _ in run]
    speeds = np.array([speed for *_, speed in run])
    assert modes[0] == POINT_MODE and modes[-1] == POINT_MODE
    assert all(mode == STREAK_MODE for mode, speed in zip(modes, speeds, strict=True) if speed >= 7.5 * DEG)
    switched = [k for k, (_, step, _, _) in enumerate(run) if step.extra["switched"]]
    assert len(switched) == 2 and modes[switched[0]] == STREAK_MODE and modes[switched[1]] == POINT_MODE
    # into streak mode on the way up past the 12 px threshold (4.8 deg/s here), out below the 8 px one
    assert 4.0 * DEG <= speeds[switched[0]] <= 8.0 * DEG and speeds[switched[1]] <= 3.2 * DEG
    assert any(step.mode == "streak tracking" for _, step, mode, _ in run if mode == STREAK_MODE)


def test_the_rate_follows_the_slew_in_streak_mode(run):
    for truth, step, mode, speed in run:
        if mode == STREAK_MODE and step.mode == "streak tracking":
            true = slew_rate([truth.t_mid_s])[0]
            assert np.linalg.norm(step.rate_rad_s - true) < 0.05 * speed  # 5 % of the rate
