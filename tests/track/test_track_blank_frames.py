"""A blank (constant) frame, or a noise-free one, with an exposure time known: the image's smear is
not measurable there (0 px) and the point detector decides, whatever the tracker's state.

Before: the smear measure (rate.image_smear_px -> find_streak_candidates) raised "image has no noise
to set a threshold by", so a blank frame after a tracked one was TOO_FEW_STARS (its smear came from
the rate) and the next blank frame an error; a noise-free simulated frame that solve_image solves
was an error row of `startrack track`."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import Camera, Status
from startrack.frames import attitude_error, random_rotations
from startrack.identify._field_stars import field_stars
from startrack.rate import image_smear_px
from startrack.simulate import simulate_frame
from startrack.track import Tracker
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(512, 512, 15.0)
PIXEL = CAMERA.pixel_scale_arcsec * ARCSEC
EXPOSURE_S = 0.02
BLANKS = [np.full((512, 512), 100, dtype=np.uint16), np.zeros((512, 512)), np.full((512, 512), 7.5, np.float32)]


def _stars(rot):
    """The 40 brightest catalog stars (V 7) in the image of an attitude (px, exact)."""
    stars = field_stars(7.0, 2000.0)
    cam = rot.apply(stars.vectors)
    front = np.flatnonzero(cam[:, 2] > 0.9)
    x, y = CAMERA.vector_to_pixel(cam[front])
    inside = np.flatnonzero(CAMERA.in_image(x, y, margin_px=1.0))[:40]
    return x[inside], y[inside]


@pytest.mark.parametrize("blank", BLANKS, ids=["uint16", "zeros", "float32"])
def test_a_blank_frame_is_too_few_stars_whatever_the_tracker_knows(blank):
    assert image_smear_px(blank) == 0.0  # px; raised InvalidInputError
    fresh = Tracker(width=512, height=512, fov_deg=15.0).update_image(blank, 0.1, streak_exposure_s=EXPOSURE_S)
    assert fresh.status is Status.TOO_FEW_STARS and fresh.extra["streak_px"] == 0.0

    rate = np.array([0.5, -0.3, 0.1]) * DEG
    start = random_rotations(None, rng=11)
    tracker = Tracker(camera=CAMERA)
    for k in range(3):  # an attitude and a rate from star lists
        assert tracker.update(*_stars(start), 0.1 * k, gyro_rate_rad_s=rate).status is Status.OK
    statuses = [tracker.update_image(blank, 0.3 + 0.1 * k, streak_exposure_s=EXPOSURE_S).status for k in range(3)]
    assert statuses == [Status.TOO_FEW_STARS] * 3  # the second raised (the rate was forgotten by the first)


def test_a_blank_frame_at_a_streaking_rate_is_too_few_stars():
    blank = BLANKS[0]
    gyro = np.array([20.0, 0.0, 0.0]) * DEG  # 25 px of smear in 0.02 s: streak mode
    step = Tracker(camera=CAMERA).update_image(blank, 0.0, streak_exposure_s=EXPOSURE_S, gyro_rate_rad_s=gyro)
    assert step.status is Status.TOO_FEW_STARS and step.extra["streak_px"] > 12.0  # px: the streak-on default

    start = random_rotations(None, rng=12)
    tracker = Tracker(camera=CAMERA)
    assert tracker.update(*_stars(start), 0.0).status is Status.OK
    step = tracker.update_image(blank, 0.1, streak_exposure_s=EXPOSURE_S, gyro_rate_rad_s=gyro)
    assert step.status is Status.TOO_FEW_STARS  # streak tracking measured a noise of 0 and raised


def test_a_noise_free_frame_is_solved_as_point_stars():
    truth = random_rotations(None, rng=5)
    image = simulate_frame(CAMERA, truth, max_mag=7.0, rng=1, noise=False).image
    assert image_smear_px(image) == 0.0  # px: no noise to measure the streak candidates against
    step = Tracker(width=512, height=512, fov_deg=15.0).update_image(image, 0.0, streak_exposure_s=EXPOSURE_S)
    assert step.status is Status.OK and step.mode == "lost-in-space"
    assert attitude_error(truth, step.rot_cam_from_icrs) < 2 * PIXEL
