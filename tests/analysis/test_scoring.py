"""The benchmark's judge: roll is weighted by the image's half-diagonal over the focal length."""

import math

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.analysis import _scoring as scoring
from startrack.units import ARCSEC


def test_pure_roll_counts_as_the_motion_it_causes_at_the_corner():
    camera = Camera.from_fov(1024, 1024, 8.0)
    truth = Rotation.from_euler("zyx", [10, 20, 30], degrees=True)
    roll = Rotation.from_rotvec([0.0, 0.0, 150 * ARCSEC])  # about the camera's boresight
    weight = scoring.roll_weight(camera)
    assert weight == np.float64(math.hypot(512, 512) / camera.fx)
    err = scoring.attitude_errors_rad([truth], [roll.inv() * truth], weight)[0]
    assert math.isclose(err, weight * 150 * ARCSEC, rel_tol=1e-6)
    assert err < scoring.tolerance_rad(camera) < 150 * ARCSEC  # a 150" roll error is no false solve at 8 deg


def test_cross_boresight_error_is_unweighted_and_never_above_the_total_angle():
    truth = Rotation.from_euler("zyx", [40, -10, 5], degrees=True)
    rng = np.random.default_rng(3)
    for _ in range(20):
        delta = Rotation.from_rotvec(rng.normal(0, 1e-3, 3))
        total = (delta.inv()).magnitude()
        weighted = scoring.attitude_errors_rad([truth], [delta.inv() * truth], 0.1)[0]
        assert weighted <= total + 1e-15
    tilt = Rotation.from_rotvec([2e-4, 0.0, 0.0])
    assert math.isclose(scoring.attitude_errors_rad([truth], [tilt.inv() * truth], 0.1)[0], 2e-4, rel_tol=1e-9)
    assert np.isnan(scoring.attitude_errors_rad([truth], [None])[0])
