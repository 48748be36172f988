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


def _wide_list(seed: int, sigma_px: float = 0.2, max_mag: float = 7.5, camera: Camera = WIDE, min_cos: float = 0.9):
    """Catalog stars (V <= max_mag, J2000) in ``camera`` at a random attitude (those whose angle
    to the boresight has a cosine above ``min_cos`` projected), brightest first, with Gaussian
    centroid noise ``sigma_px`` (px); and the true attitude."""
    rng = np.random.default_rng(seed)
    truth = random_rotations(rng=rng)
    v_cam = truth.apply(field_stars(max_mag, 2000.0).vectors)
    x, y = camera.vector_to_pixel(v_cam[v_cam[:, 2] > min_cos])
    x, y = x + rng.normal(0, sigma_px, x.shape), y + rng.normal(0, sigma_px, y.shape)
    inside = camera.in_image(x, y)
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


LANDSCAPE = Camera(width=4000, height=1000, fx=1.0 / np.tan(np.radians(31.2)) * 2000, k1=-0.05)
"""A wide distorted lens (about 62 x 17 deg), calibrated nowhere: the solve fits its k1."""


@pytest.mark.parametrize("held", ["landscape", "portrait"])
def test_a_wide_lens_is_fitted_as_wide_whichever_way_the_image_is_held(held):
    """Before: a portrait image's wide side was not seen (the horizontal field of view, 17 deg, was
    the test), so its k1 went unfitted and about a third of its stars unmatched."""
    camera = LANDSCAPE if held == "landscape" else Camera(width=1000, height=4000, fx=LANDSCAPE.fx, fy=LANDSCAPE.fy,
                                                          k1=LANDSCAPE.k1)
    x, y, truth = _wide_list(4, sigma_px=0.1, max_mag=6.5, camera=camera, min_cos=0.5)
    solution = solve_stars(x, y, width=camera.width, height=camera.height)
    assert solution.status is Status.OK, solution.reason
    assert len(solution.matches.hip) >= 0.95 * x.size  # every star but a close pair or two
    assert solution.camera.k1 == pytest.approx(camera.k1, abs=0.005)  # k1, unitless: 10 % of the lens's
