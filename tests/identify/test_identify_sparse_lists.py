"""A list of only a field's few brightest stars: knowing the field of view must not make it
unsolvable. Its patterns can lie in the database levels next to the field's, which the search
with the field of view given left out (15 of 20 such six-star lists solved with fov_deg=15, 20 of
20 with nothing given); a search that finds nothing now looks one level further each way."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import Camera, Status, solve_stars
from startrack.frames import attitude_error, random_rotations
from startrack.identify._field_stars import field_stars
from startrack.units import ARCSEC

CAMERA = Camera.from_fov(1024, 1024, 15.0)


def _brightest(seed: int, n: int = 6):
    """The ``n`` brightest catalog stars (V <= 7.5, J2000, exact positions) of the camera's field
    at a random attitude, and that attitude."""
    truth = random_rotations(rng=np.random.default_rng(seed))
    v = truth.apply(field_stars(7.5, 2000.0).vectors)
    x, y = CAMERA.vector_to_pixel(v[v[:, 2] > 0.9])
    inside = CAMERA.in_image(x, y)
    return x[inside][:n], y[inside][:n], truth


@pytest.mark.parametrize("seed", [100, 103, 104])  # lists the field's own levels did not solve
def test_six_brightest_stars_solve_with_the_field_of_view_given(seed):
    x, y, truth = _brightest(seed)
    for given in ({"fov_deg": 15.0}, {"camera": CAMERA}):
        solution = solve_stars(x, y, width=1024, height=1024, **given)
        assert solution.status is Status.OK, solution.reason
        # exact positions: within a pixel angle (52 arcsec), roll from six stars included
        assert attitude_error(truth, solution.rot_cam_from_icrs) < CAMERA.pixel_scale_arcsec * ARCSEC
