"""Tracker.update / update_image refuse non-finite inputs, naming the parameter (issue 19)."""

import numpy as np
import pytest

from startrack import Camera
from startrack.errors import InvalidInputError
from startrack.track import Tracker

CAMERA = Camera.from_fov(256, 256, 12.0)
XY = (np.array([10.0, 20.0, 30.0]), np.array([40.0, 50.0, 60.0]))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_update_refuses_non_finite_positions_and_times(bad):
    tracker = Tracker(camera=CAMERA)
    x, y = XY
    with pytest.raises(InvalidInputError, match=r"^x must hold finite pixel positions; entry 1"):
        tracker.update(np.array([1.0, bad, 3.0]), y, 0.0)
    with pytest.raises(InvalidInputError, match=r"^y must hold finite"):
        tracker.update(x, np.array([bad, 1.0, 2.0]), 0.0)
    with pytest.raises(InvalidInputError, match=r"^t_s must be a finite number of seconds"):
        tracker.update(x, y, bad)
    with pytest.raises(InvalidInputError, match=r"^gyro_rate_rad_s must be 3 finite numbers"):
        tracker.update(x, y, 0.0, gyro_rate_rad_s=[0.0, bad, 0.0])
    with pytest.raises(InvalidInputError, match=r"^flux must be finite"):
        tracker.update(x, y, 0.0, flux=[1.0, bad, 2.0])


def test_update_refuses_mismatched_or_non_numeric_stars():
    tracker = Tracker(camera=CAMERA)
    with pytest.raises(InvalidInputError, match="x and y must be 1-D arrays of one length"):
        tracker.update(np.zeros(3), np.zeros(2), 0.0)
    with pytest.raises(InvalidInputError, match="flux must have one entry per star"):
        tracker.update(*XY, 0.0, flux=[1.0])
    with pytest.raises(InvalidInputError, match="t_s must be a finite number"):
        tracker.update(*XY, "soon")


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_update_image_refuses_non_finite_times_and_rates(bad):
    tracker = Tracker(camera=CAMERA)
    image = np.zeros((256, 256))
    with pytest.raises(InvalidInputError, match=r"^t_s must be a finite number of seconds"):
        tracker.update_image(image, bad)
    with pytest.raises(InvalidInputError, match=r"^gyro_rate_rad_s must be 3 finite numbers"):
        tracker.update_image(image, 0.0, gyro_rate_rad_s=[bad, 0.0, 0.0], streak_exposure_s=0.1)
    with pytest.raises(InvalidInputError, match=r"^gyro_rate_rad_s"):
        tracker.update_image(image, 0.0, gyro_rate_rad_s=[bad, 0.0, 0.0], streak_exposure_s=0.1,
                             streak_bias_px=0.5)


@pytest.mark.parametrize("exposure", ["x", [], np.zeros(3), 0.0, -1.0, np.nan, True, 1e-7, 1.1e6, 1e300])
def test_update_image_refuses_an_exposure_that_is_not_a_positive_number(exposure):
    # before: TypeError ("'>' not supported between 'str' and 'int'") or numpy's "truth value ... ambiguous";
    # 1e-7 s and 1e300 s were taken, where the rate functions refuse them (one range since)
    words = r"^streak_exposure_s \(seconds, or None\) must be a finite number >= 1e-06 and <= 1e\+06, got "
    with pytest.raises(InvalidInputError, match=words):
        Tracker(camera=CAMERA).update_image(np.zeros((256, 256)), 0.0, streak_exposure_s=exposure)


def test_update_image_refuses_a_detector_that_is_not_one_and_a_flux_of_words():
    # before: AttributeError ("'float' object has no attribute 'detect'"), ValueError from numpy
    with pytest.raises(InvalidInputError, match=r"^detector must be a startrack.detect.StarDetector, got a float"):
        Tracker(camera=CAMERA).update_image(np.zeros((256, 256)), 0.0, detector=5.0)
    with pytest.raises(InvalidInputError, match=r"^flux must be a number or an array of numbers, got 'x'"):
        Tracker(camera=CAMERA).update(*XY, 0.0, flux="x")


def test_empty_star_list_is_an_expected_failure_not_an_error():
    step = Tracker(camera=CAMERA).update(np.zeros(0), np.zeros(0), 0.0)
    assert not step.status and step.reason
