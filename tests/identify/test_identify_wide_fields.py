"""Wide fields (a long side several times the short one): knowing the field of view must not
make a list unsolvable that the search with the field of view unknown solves. The database's
levels are chosen by the image's area (``SearchSetup.square_px``), not its short side alone."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import Camera, Status, solve_stars
from startrack.frames import attitude_error, random_rotations
from startrack.identify._field_stars import field_stars
from startrack.units import ARCSEC

WIDE = Camera.from_fov(3000, 600, 10.0)
"""10 x 2 deg: its short side alone reaches no level of the default database (5 deg and up)."""


def _wide_list(seed: int, sigma_px: float = 0.2, max_mag: float = 7.5):
    """Catalog stars (V <= max_mag, J2000) in the wide camera at a random attitude, brightest
    first, with Gaussian centroid noise ``sigma_px`` (px); and the true attitude."""
    rng = np.random.default_rng(seed)
    truth = random_rotations(rng=rng)
    v_cam = truth.apply(field_stars(max_mag, 2000.0).vectors)
    x, y = WIDE.vector_to_pixel(v_cam[v_cam[:, 2] > 0.9])
    x, y = x + rng.normal(0, sigma_px, x.shape), y + rng.normal(0, sigma_px, y.shape)
    inside = WIDE.in_image(x, y)
    return x[inside], y[inside], truth


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("knowledge", ["fov_deg", "camera", "nothing"])
def test_a_wide_field_solves_with_or_without_its_field_of_view(seed, knowledge):
    x, y, truth = _wide_list(seed)
    assert x.size >= 8  # enough stars that the search, not the list, decides
    given = {"fov_deg": {"fov_deg": 10.0}, "camera": {"camera": WIDE}, "nothing": {}}[knowledge]
    solution = solve_stars(x, y, width=WIDE.width, height=WIDE.height, **given)
    assert solution.status is Status.OK, solution.reason
    # within 2 pixel angles (12 arcsec px): the attitude of ~10 stars with 0.2 px noise
    assert attitude_error(solution.rot_cam_from_icrs, truth) < 2 * WIDE.pixel_scale_arcsec * ARCSEC
