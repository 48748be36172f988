"""simulate_frame's arguments are checked by name before any work. A probe of its parameters with
numbers, words, lists, dicts and arrays in the wrong places found AttributeError ("'int' object has no
attribute 'exposure_s'"), TypeError and OverflowError; each is now an InvalidInputError naming the
argument and what it must be."""

from __future__ import annotations

import re

import numpy as np
import pytest

from startrack import Camera
from startrack.errors import InvalidInputError
from startrack.simulate import random_attitude, simulate_frame

CAMERA = Camera.from_fov(64, 64, 15.0)


@pytest.mark.parametrize("argument, value, words", [
    ("camera", "far-mst", "camera must be a startrack.camera.Camera, got a str"),
    ("sensor", 0.2, "sensor must be a startrack.simulate.Sensor, got a float"),
    ("timing", 0.0, "timing must be a startrack.simulate.FrameTiming, got a float"),
    ("sky", np.zeros(3), "sky must be a startrack.simulate.SkyModel, got a ndarray"),
    ("radius_sigmas", None, "radius_sigmas must be a number, got None"),
    ("radius_sigmas", 1e300, "radius_sigmas must be at most 50 PSF sigmas, got 1e+300"),
    ("rng", -1, "rng must be a numpy Generator, a seed (an integer >= 0, or a sequence of them) or None, got -1"),
    ("rng", "x", "rng must be a numpy Generator"),
    ("rate_rad_s", "x", "rate_rad_s must be a number or an array of numbers, got 'x'"),
    ("background_e", {}, "background_e must be a number or an array of numbers, got {}"),
])
def test_a_wrong_argument_is_refused_by_name(argument, value, words):
    kwargs = {"camera": CAMERA, "rot_cam_from_icrs": random_attitude(rng=1), "max_mag": 5.0, "rng": 1}
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        simulate_frame(**(kwargs | {argument: value}))


@pytest.mark.parametrize("width", [None, "64", [64], 1])
def test_from_fov_checks_the_width_before_using_it(width):
    # before: TypeError ("unsupported operand type(s) for /: 'NoneType' and 'float'")
    with pytest.raises(InvalidInputError, match=re.escape(f"camera width must be an integer of at least 2 px, "
                                                          f"got {width!r}")):
        Camera.from_fov(width, 64, 15.0)
