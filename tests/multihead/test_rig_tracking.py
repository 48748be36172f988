"""The Tracker with a rig: every head's windows from the joint attitude and rate, tracking on
while one head is blinded, the heads that contributed reported."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Status
from startrack.errors import InvalidInputError
from startrack.frames import random_rotations
from startrack.simulate._rig import rig_star_lists
from startrack.track import Tracker
from startrack.track._tracker import LOST_IN_SPACE, TRACKING
from startrack.units import ARCSEC, DEG

from .rigs import CAMERA, two_heads


def test_tracking_continues_through_a_blinded_head_and_reports_the_heads():
    rig, rng = two_heads(), np.random.default_rng(21)
    start = random_rotations(None, rng)
    rate = np.array([0.5, -0.3, 0.2]) * DEG  # body frame
    tracker = Tracker(rig=rig)
    steps = []
    for k in range(10):
        t = 0.1 * k
        truth = Rotation.from_rotvec(-rate * t) * start
        stars = {n: s.stars for n, s in rig_star_lists(rig, truth, rng=rng, sigma_px=0.2).items()}
        if 4 <= k <= 6:
            stars["a"] = (np.zeros(0), np.zeros(0))  # head a blinded
        step = tracker.update_rig(stars, t)
        assert step.status is Status.OK
        assert (truth * step.rot_body_from_icrs.inv()).magnitude() < 30 * ARCSEC
        steps.append(step)
    assert steps[0].mode == LOST_IN_SPACE and all(s.mode == TRACKING for s in steps[1:])
    assert [s.heads for s in steps[3:8]] == [("a", "b"), ("b",), ("b",), ("b",), ("a", "b")]
    assert steps[5].n_matched["a"] == 0 and steps[5].n_matched["b"] >= 5
    np.testing.assert_allclose(steps[-1].rate_body_rad_s, rate, atol=0.02 * DEG)
    tracker.reset()
    stars = {n: s.stars for n, s in rig_star_lists(rig, start, rng=rng).items()}
    assert tracker.update_rig(stars, 5.0).mode == LOST_IN_SPACE


def test_a_rig_tracker_refuses_single_camera_use_and_the_other_way_round():
    with pytest.raises(InvalidInputError, match="a rig has its cameras"):
        Tracker(rig=two_heads(), camera=CAMERA)
    with pytest.raises(InvalidInputError, match="update_rig"):
        Tracker(rig=two_heads()).update([1.0], [2.0], 0.0)
    with pytest.raises(InvalidInputError, match="Tracker\\(rig=...\\)"):
        Tracker(camera=CAMERA).update_rig({}, 0.0)
    with pytest.raises(InvalidInputError, match="gyro_rate_rad_s"):
        Tracker(rig=two_heads()).update_rig({}, 0.0, gyro_rate_rad_s=[1.0])
