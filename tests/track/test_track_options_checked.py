"""TrackerOptions refuses every setting the tracker cannot use, naming the field and its range
(a gain of 5 gave a wrong rate; min_stars=0 a LinAlgError on an empty frame and, with one star,
an OK attitude 4 deg off)."""

import numpy as np
import pytest

from startrack import Camera, Status
from startrack.errors import InvalidInputError
from startrack.frames import random_rotations
from startrack.identify._field_stars import field_stars
from startrack.track import Tracker, TrackerOptions
from startrack.track._tracker import MIN_TRACKED_STARS
from startrack.units import ARCSEC

CAMERA = Camera.from_fov(1024, 1024, 15.0)
PIXEL = CAMERA.pixel_scale_arcsec * ARCSEC

REFUSED = [
    ("rate_gain", 0.0, r"^rate_gain must be a number with 0 < rate_gain <= 1"),
    ("rate_gain", -1.0, r"^rate_gain must be a number with 0 < rate_gain <= 1"),
    ("rate_gain", 5.0, r"^rate_gain must be a number with 0 < rate_gain <= 1"),
    ("rate_gain", float("nan"), r"^rate_gain must be"),
    ("rate_gain", "0.5", r"^rate_gain must be"),
    ("min_stars", 0, r"^min_stars must be an integer >= 2, got 0"),
    ("min_stars", 1, r"^min_stars must be an integer >= 2, got 1"),
    ("min_stars", -3, r"^min_stars must be an integer >= 2"),
    ("min_stars", 2.5, r"^min_stars must be an integer >= 2, got 2.5"),
    ("min_stars", True, r"^min_stars must be an integer"),
    ("window_px", -5.0, r"^window_px must be a positive number, got -5.0"),
    ("window_px", 0.0, r"^window_px must be a positive number"),
    ("match_px", float("nan"), r"^match_px must be a positive number, got nan"),
    ("max_residual_px", float("nan"), r"^max_residual_px must be a positive number"),
    ("max_residual_px", float("inf"), r"^max_residual_px must be a positive number"),
    ("max_rate_deg_s", -1.0, r"^max_rate_deg_s must be a number >= 0"),
    ("rate_error_fraction", float("inf"), r"^rate_error_fraction must be a number >= 0, got inf"),
    ("rate_error_fraction", -0.1, r"^rate_error_fraction must be a number >= 0"),
    ("catalog_max_mag", float("nan"), r"^catalog_max_mag must be a finite number"),
    ("target_stars", 0, r"^target_stars must be an integer >= 1 or None, got 0"),
    ("target_stars", 10.0, r"^target_stars must be an integer >= 1 or None"),
    ("streak_on_px", "12", r"^streak_off_px must be positive and at most streak_on_px"),
    ("streak_off_px", float("nan"), r"^streak_off_px must be positive and at most streak_on_px"),
]


@pytest.mark.parametrize(("name", "value", "message"), REFUSED)
def test_a_setting_out_of_its_range_is_refused_naming_it(name, value, message):
    with pytest.raises(InvalidInputError, match=message):
        TrackerOptions(**{name: value})


@pytest.mark.parametrize("settings", [
    {"rate_gain": 1.0}, {"rate_gain": 1e-3}, {"min_stars": MIN_TRACKED_STARS}, {"min_stars": np.int64(7)},
    {"max_rate_deg_s": 0.0}, {"rate_error_fraction": 0.0}, {"window_px": 3}, {"target_stars": None},
    {"target_stars": 30}, {"catalog_max_mag": 6}, {"streak_on_px": float("inf")},
])
def test_settings_in_range_are_kept(settings):
    options = TrackerOptions(**settings)
    for name, value in settings.items():
        assert getattr(options, name) == value or getattr(options, name) is value


def _stars(rot, count: int):
    """The ``count`` brightest catalog stars in the image of an attitude (px, exact)."""
    stars = field_stars(7.0, 2000.0)
    cam = rot.apply(stars.vectors)
    front = np.flatnonzero(cam[:, 2] > 0.9)
    x, y = CAMERA.vector_to_pixel(cam[front])
    inside = np.flatnonzero(CAMERA.in_image(x, y, margin_px=1.0))[:count]
    return x[inside], y[inside]


def test_the_fewest_stars_allowed_still_fix_the_attitude():
    truth = random_rotations(None, rng=4)
    tracker = Tracker(camera=CAMERA, options=TrackerOptions(min_stars=MIN_TRACKED_STARS))
    assert tracker.update(*_stars(truth, 40), 0.0).status is Status.OK
    step = tracker.update(*_stars(truth, 2), 0.1)  # two stars: tracked (one left the roll free)
    assert step.status is Status.OK and step.n_matched == 2
    assert (truth * step.rot_cam_from_icrs.inv()).magnitude() < 0.1 * PIXEL
    empty = tracker.update(np.zeros(0), np.zeros(0), 0.2)  # raised LinAlgError with min_stars=0
    assert empty.status is Status.TOO_FEW_STARS
