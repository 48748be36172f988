"""The Tracker through a slew that speeds up to 8 deg/s and back (issue 19): an attitude on every
frame, point mode at rest, streak mode at speed, and the switches between them."""

import numpy as np
import pytest
from slew_frames import CAMERA, EXPOSURE_S, slew_rate

from startrack.frames import attitude_error
from startrack.track import Tracker
from startrack.track._tracker import POINT_MODE, STREAK_MODE
from startrack.units import DEG


@pytest.fixture(scope="module")
def run(slew_frames):
    tracker = Tracker(width=512, height=512, fov_deg=20.0, epoch=2025.0)
    out = []
    for sim in slew_frames:
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
