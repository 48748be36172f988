"""The rig tracker checks a frame's time as the single-camera tracker does, before its state changes:
an infinite time used to return OK and leave an attitude that broke every later frame."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import Status
from startrack.errors import InvalidInputError
from startrack.frames import random_rotations
from startrack.multihead import RigOptions, RigTracker
from startrack.simulate._rig import rig_star_lists
from startrack.track import TRACKING, Tracker, TrackerOptions
from startrack.units import ARCSEC

from .rigs import two_heads


@pytest.fixture(scope="module")
def frame():
    rig = two_heads()
    truth = random_rotations(None, np.random.default_rng(7))
    lists = rig_star_lists(rig, truth, rng=0, sigma_px=0.2, max_mag=6.0)
    return rig, truth, {n: s.stars for n, s in lists.items()}


@pytest.mark.parametrize("bad", [float("inf"), float("-inf"), float("nan"), "soon", None])
def test_a_bad_time_is_refused_and_leaves_the_tracker_as_it_was(frame, bad):
    rig, truth, stars = frame
    tracker = Tracker(rig=rig)
    assert tracker.update_rig(stars, 0.0).status is Status.OK
    with pytest.raises(InvalidInputError, match=r"^t_s must be a finite number of seconds, got "):
        tracker.update_rig(stars, bad, gyro_rate_rad_s=[0.1, 0.2, 0.3])
    step = tracker.update_rig(stars, 0.1)  # raised "Found zero norm quaternions" after an infinite time
    assert step.status is Status.OK and step.mode == TRACKING
    assert (truth * step.rot_body_from_icrs.inv()).magnitude() < 30 * ARCSEC
    np.testing.assert_allclose(step.rate_body_rad_s, 0.0, atol=2 * ARCSEC / 0.1)  # rad/s: the gyro rate was not taken


def test_the_rig_tracker_refuses_options_of_another_class(frame):
    rig = frame[0]
    with pytest.raises(InvalidInputError, match="options of the RigTracker must be a startrack.track.TrackerOptions"):
        RigTracker(rig, options=RigOptions())
    with pytest.raises(InvalidInputError, match="rig_options of the RigTracker must be a startrack.multihead.RigOpt"):
        RigTracker(rig, rig_options=TrackerOptions())
    with pytest.raises(InvalidInputError, match="options of the Tracker must be"):
        Tracker(rig=rig, options=RigOptions())
