"""Arguments of the wrong type or out of range, refused by name before any work. A probe of the public
functions of startrack.multihead, .calibrate, .attitude, .catalog and .detect with numbers, words, lists, dicts and
arrays in the wrong places found AttributeError ("'int' object has no attribute 'names'"), TypeError
("'int' object is not iterable"), ZeroDivisionError and numpy's ValueError; each case below raised one
of them before."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from multihead.rigs import two_heads
from startrack import Camera
from startrack.attitude import average_quaternions, propagate
from startrack.calibrate import CalibrationFrame, calibrate_from_stars
from startrack.catalog import cone_search, load_catalog, thin_uniform
from startrack.detect import calibrate_zero_point, flux_for_snr, instrument_magnitude
from startrack.errors import InvalidInputError, checked_rng
from startrack.multihead import rig_availability, solve_rig

CAMERA = Camera.from_fov(1024, 1024, 15.0)
XY = np.array([100.0, 300, 500, 700]), np.array([100.0, 200, 600, 300])
VECTORS = np.tile([0.0, 0.0, 1.0], (4, 1))
FRAME = CalibrationFrame(*XY, VECTORS, Rotation.identity())


@pytest.mark.parametrize("call, words", [
    (lambda: calibrate_from_stars(3, CAMERA), "frames must be a CalibrationFrame or a list of them, got a int"),
    (lambda: calibrate_from_stars(FRAME, CAMERA, fit=[]), "fit must be a tuple of one or more parameter names"),
    (lambda: calibrate_from_stars(FRAME, CAMERA, model=0), "model must be a BrownConradyModel, a TiltedCcdModel or"),
    (lambda: CalibrationFrame("x", XY[1], VECTORS, Rotation.identity()), "x must be a number or an array of numbers"),
    (lambda: solve_rig({}, two_heads(), options="x"), "options must be a startrack.multihead.RigOptions, got a str"),
    (lambda: rig_availability(0, 5.0, 10), "rig must be a startrack.rig.CameraRig, got a int"),
    (lambda: rig_availability(two_heads(), "x", 10), "max_mag (V) must be a finite number >= -2 and <= 20"),
    (lambda: rig_availability(two_heads(), 5.0, 10**30), "n_pointings must be an integer >= 1 and <= 100000000"),
    (lambda: rig_availability(two_heads(), 5.0, 10, min_stars=None), "min_stars must be an integer >= 1, got None"),
    (lambda: rig_availability(two_heads(), 5.0, 10, bodies=0), "bodies must be a startrack.multihead.BrightBodies"),
    (lambda: propagate(0, [0, 0, 0.1], 1.0), "rot_cam_from_icrs must be a scipy.spatial.transform"),
    (lambda: propagate(Rotation.identity(), [0, 0, 0.1], "x"), "dt_s must be a number or an array of numbers"),
    (lambda: propagate(Rotation.identity(), [0, 0, 0.1], 1e300), "omega_rad_s * dt_s turns through 1e+299 rad"),
    (lambda: propagate(Rotation.identity(), [0, 0, 0.1], 1.0, frame=np.zeros(3)), "frame must be one of camera, icrs"),
    (lambda: average_quaternions("x"), "quaternions must be a number or an array of numbers, got 'x'"),
    (lambda: cone_search("hip", [0, 0, 1.0], 0.1), "catalog must be a startrack.catalog.StarCatalog, got a str"),
    (lambda: cone_search(load_catalog(), [0, 0, 1.0], "x"), "radius_rad must be in [0, pi] radians, got 'x'"),
    (lambda: thin_uniform(load_catalog(), 5, 1e-300), "region_radius_rad (radians) must be a finite number >= 0.001"),
    (lambda: thin_uniform(load_catalog(), None, 0.1), "max_per_region must be an integer >= 1, got None"),
    (lambda: thin_uniform(load_catalog(), 5, 0.1, band=np.zeros(3)), "band must be one of"),
    (lambda: instrument_magnitude([1.0, 2.0], zero_point="x"), "zero_point (mag) must be a finite number, got 'x'"),
    (lambda: calibrate_zero_point("x", [1.0]), "flux must be a number or an array of numbers, got 'x'"),
    (lambda: flux_for_snr({}, 1.5, 100.0, 5.0), "snr must be a number or an array of numbers, got {}"),
    (lambda: checked_rng("x"), "rng must be a numpy Generator, a seed (an integer >= 0, or a sequence of them)"),
])
def test_a_wrong_argument_is_refused_by_name(call, words):
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        call()
