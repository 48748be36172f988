"""The window matcher's cached catalog cone when the boresight jumps to the opposite side of the sky
(two heads' star lists swapped in a rig solve): the angle moved is pi, not a math domain error."""

import math

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.identify._field_stars import field_stars
from startrack.track._windows import WindowMatcher, _angle_rad

CAMERA = Camera.from_fov(512, 512, 15.0)
FLIP = np.diag([1.0, -1.0, -1.0])  # a half turn about the camera x axis: the boresight row negated exactly


def _antipodal_pair() -> tuple[np.ndarray, np.ndarray]:
    """Two attitudes whose boresights are exact opposites with a rounded dot product below -1."""
    matrix = Rotation.random(random_state=1).as_matrix()
    assert sum(u * -u for u in matrix[2].tolist()) < -1.0  # the float sum the old acos was given
    return matrix, FLIP @ matrix


def test_the_cone_cache_follows_the_boresight_to_its_antipode():
    first, second = _antipodal_pair()
    matcher = WindowMatcher(CAMERA, field_stars(6.5, 2000.0))
    matcher.predicted(first, 0.01, 30)
    idx, x, y = matcher.predicted(second, 0.01, 30)  # raised "math domain error"
    assert idx.size > 0 and np.all(CAMERA.in_image(x, y))
    np.testing.assert_allclose(matcher._centre, second[2])  # the cone was queried again around the new boresight


def test_the_angle_is_exact_at_both_ends():
    u = tuple(Rotation.random(random_state=1).as_matrix()[2].tolist())
    opposite = tuple(-c for c in u)
    assert _angle_rad(u, opposite) == math.pi
    assert _angle_rad(u, u) == 0.0
    small = Rotation.from_rotvec([1e-9, 0.0, 0.0]).apply(u).tolist()
    # rad; the rotated components carry 1e-16 rounding (acos of the dot, rounded to 1.0, gives 0 here)
    assert abs(_angle_rad(u, tuple(small)) - 1e-9 * math.hypot(u[1], u[2])) < 1e-15  # rad
