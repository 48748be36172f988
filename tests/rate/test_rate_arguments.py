"""The rate functions check their arguments by name before any work. A probe of streak_rate,
solve_streaked, catalog_free_rate, find_streaks, choose_mode and calibrate.focal_from_stars with
numbers, words, lists, dicts and arrays in the wrong places found AttributeError ("'int' object has
no attribute 'fx'"), IndexError, OverflowError, ZeroDivisionError and numpy's TypeError and
ValueError; each case below raised one of them before."""

from __future__ import annotations

import re

import numpy as np
import pytest

from startrack import Camera
from startrack.calibrate import focal_from_stars
from startrack.errors import InvalidInputError
from startrack.rate import catalog_free_rate, choose_mode, find_streaks, solve_streaked, streak_rate

CAMERA = Camera.from_fov(64, 64, 12.0)
IMAGE = np.zeros((64, 64))
VECTORS = np.tile([0.0, 0.0, 1.0], (4, 1))


@pytest.mark.parametrize("call, words", [
    (lambda: streak_rate(IMAGE, "far-mst", 1.0), "camera must be a startrack.camera.Camera, got a str"),
    (lambda: streak_rate(IMAGE, CAMERA, 1.0, measurement=np.zeros(3)), "measurement must be a startrack.rate"),
    (lambda: streak_rate(IMAGE, CAMERA, 1e300), "exposure_s (seconds) must be a finite number >= 1e-06 and <= 1e+06"),
    (lambda: streak_rate(IMAGE, CAMERA, 1.0, k_sigma="2"), "k_sigma must be a finite number > 0, got '2'"),
    (lambda: streak_rate("x", CAMERA, 1.0), "image must be a number or an array of numbers, got 'x'"),
    (lambda: solve_streaked(5.0, fov_deg=12.0), "image must be a 2-D array (H, W), got shape ()"),
    (lambda: solve_streaked(IMAGE, fov_deg=12.0, exposure_s=1e-300), "exposure_s (seconds) must be a finite number"),
    (lambda: solve_streaked(IMAGE, fov_deg=12.0, prior_omega_rad_s="x"), "prior_omega_rad_s must be a number or"),
    (lambda: catalog_free_rate(VECTORS, VECTORS, 1.0, max_rounds=0), "max_rounds must be an integer >= 1 and <= 1000"),
    (lambda: catalog_free_rate(VECTORS, VECTORS, 1.0, min_streaks="x"), "min_streaks must be an integer >= 2"),
    (lambda: catalog_free_rate("x", VECTORS, 1.0), "vectors_a must be a number or an array of numbers, got 'x'"),
    (lambda: catalog_free_rate(VECTORS, VECTORS, 1.0, initial_used=[True]), "initial_used must be 4 booleans"),
    (lambda: find_streaks(IMAGE, smooth_sigma_px=1e300), "smooth_sigma_px must be a finite number >= 0 and <= 50"),
    (lambda: find_streaks(IMAGE, margin_px=-1), "margin_px must be an integer >= 0, got -1"),
    (lambda: find_streaks(IMAGE, rule=np.zeros(3)), "rule must be one of robust, mean"),
    (lambda: choose_mode(IMAGE, brightest=0), "brightest must be an integer >= 1, got 0"),
    (lambda: choose_mode(IMAGE, min_streak_fraction=2.0), "min_streak_fraction must be a finite number > 0 and <= 1"),
    (lambda: focal_from_stars([1.0, 2.0], [1.0], VECTORS, 32.0, 32.0), "x and y must be (K,) and vectors (K, 3)"),
    (lambda: focal_from_stars([1.0] * 4, [1.0] * 4, VECTORS, "x", 32.0), "cx must be a finite number, got 'x'"),
])
def test_a_wrong_argument_is_refused_by_name(call, words):
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        call()
