"""Wide fields (a long side several times the short one): knowing the field of view must not
make a list unsolvable that the search with the field of view unknown solves. The database's
levels are chosen by the image's area (``SearchSetup.square_px``), not its short side alone."""

from __future__ import annotations

import numpy as np
import pytest

from startrack import Camera, Status, solve_stars
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error, random_rotations
from startrack.identify import database_settings_for
from startrack.identify._field_stars import field_stars
from startrack.identify._final_fit import REFIT_OUTLIER_PX, _Field, _refit_residuals, _without_refit_outliers
from startrack.identify._refine import fit_pose
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


def _ultra_wide(fov_deg: float) -> Camera:
    """A 3:2 rectilinear lens of ``fov_deg`` horizontally with a realistic barrel (k1 = -0.005: 2-4 %
    at the corners of 120-150 deg), uncalibrated."""
    return Camera.from_fov(1800, 1200, fov_deg).with_distortion(k1=-0.005)


@pytest.mark.parametrize(("fov_deg", "given"), [(120.0, {"fov_deg": 120.0}), (150.0, {"fov_deg": 150.0}),
                                                 (135.0, {"fov_range_deg": (90.0, 150.0)})])
def test_an_ultra_wide_lens_solves_when_its_field_is_given(fov_deg, given):
    """Before: a field of view over 100 deg was refused ("must be a field of view between 0.5 and
    100 deg"), so a photo of a 12-14 mm lens could not be solved at all."""
    camera = _ultra_wide(fov_deg)
    x, y, truth = _wide_list(5, sigma_px=0.2, max_mag=5.5, camera=camera, min_cos=0.15)
    solution = solve_stars(x[:60], y[:60], width=camera.width, height=camera.height, **given)
    assert solution.status is Status.OK, solution.reason
    # within a pixel's angle at the centre (0.12-0.28 deg across these fields)
    assert attitude_error(solution.rot_cam_from_icrs, truth) < camera.pixel_scale_arcsec * ARCSEC
    assert solution.fov_deg == pytest.approx(fov_deg, rel=0.01)


@pytest.mark.parametrize("fov", [150.5, 179.0])
def test_a_field_wider_than_the_widest_is_refused_by_name(fov):
    with pytest.raises(InvalidInputError, match=r"fov_deg must be a field of view between 0.5 and 150 deg"):
        solve_stars(np.arange(10.0), np.arange(10.0), width=100, height=100, fov_deg=fov)


def test_searches_beyond_the_default_range_share_one_wide_database():
    """Each distinct range used to get a database of its own (a few seconds to build, each time a
    photo's lens differed); ranges at and above 70 deg share one that reaches the widest field."""
    shared = database_settings_for((95.0, 115.0))
    assert database_settings_for((140.0, 154.5)) == shared
    assert shared.fov_min_deg <= 70.0 and shared.fov_max_deg >= 154.5 * 1.03  # the given 150 deg, with margins
    assert database_settings_for((50.0, 120.0)) != shared  # starts below the wide fields: its own


def test_a_fit_refuses_a_step_that_scales_the_focal_length_tenfold():
    """The fit's divergence guard (``_pose_kernel.MAX_LN_FOCAL_STEP``): started 30 times too short,
    the first step would scale the focal length past the guard, and the fit keeps its start
    (before: such steps from a folding trial lens drove the focal length to zero, a
    ZeroDivisionError); started 2 times too short, it converges to the truth."""
    camera = _ultra_wide(120.0)
    x, y, truth = _wide_list(6, sigma_px=0.0, max_mag=5.0, camera=camera, min_cos=0.3)
    ref = truth.inv().apply(camera.pixel_to_vector(x, y))
    for factor, expected_fx in ((30.0, camera.fx / 30.0), (2.0, camera.fx)):
        start = camera.with_focal(camera.fx / factor, camera.fy / factor)
        matrix, fitted, residual = fit_pose(truth.as_matrix(), start, ref, x, y, fit_focal=True)
        assert np.all(np.isfinite(matrix)) and np.all(np.isfinite(residual))
        assert fitted.fx == pytest.approx(expected_fx, rel=1e-6)


def test_a_wide_candidates_wrong_star_is_dropped_before_the_k1_scan():
    """A 135 deg candidate of 8 stars on the left half, one of them given the direction of a point
    50 px from its detection: refitting the others puts it farthest (they are pulled by it too, up
    to 24 px here), it is dropped first (``REFIT_OUTLIER_PX``), and the seven left agree. Before,
    such a star stayed, and a solution settled 0.6 deg off on a focal length 2.6 % long."""
    camera = _ultra_wide(135.0)
    x, y, truth = _wide_list(7, sigma_px=0.1, max_mag=5.0, camera=camera, min_cos=0.2)
    left = np.flatnonzero((x < 0.45 * camera.width) & (np.abs(y - camera.cy) < 0.35 * camera.height))[:8]
    ref = truth.inv().apply(camera.pixel_to_vector(x[left], y[left]))
    ref[3] = truth.inv().apply(camera.pixel_to_vector(x[left[3]] + 40.0, y[left[3]] - 30.0))  # 50 px off
    field = _Field(x, y, None, fit_focal=True)  # the stars are not read by the refit
    residual = _refit_residuals(field, truth.as_matrix(), camera, left, ref)
    assert np.argmax(residual) == 3 and residual[3] == pytest.approx(50.0, abs=0.5)  # px
    kept, kept_ref = _without_refit_outliers(field, truth.as_matrix(), camera, left, ref)
    assert kept.tolist() == np.delete(left, 3).tolist() and kept_ref.shape == (7, 3)
    assert np.all(_refit_residuals(field, truth.as_matrix(), camera, kept, kept_ref) < 0.1 * REFIT_OUTLIER_PX)  # px




@pytest.mark.parametrize(("fov_deg", "k1", "before"), [(89.0, -0.12, (1444, 1787, -0.141)),
                                                       (81.8, -0.154, (1160, 1517, -0.186))])
def test_a_strongly_bent_wide_lens_settles_on_its_own_distortion(fov_deg, k1, before):
    """Strongly barrelled wide lenses, uncalibrated, whose polynomial folds back just inside the
    image's corners (no star falls beyond the fold). ``before``: stars matched, stars in the list
    and the fitted k1 when k2 was free from the first round of the re-match and at most four rounds
    were run (the first lens needs the rounds, the second k1 alone first: with 12 rounds and k2
    free from the start it still stopped on k1 = -0.185, 1,158 stars). Now k1 settles alone, then k2
    with it; on 9 such lists (81.8-89 deg, k1 -0.13 to -0.154) 7 settle right, against 2 before."""
    camera = Camera.from_fov(1920, 1080, fov_deg).with_distortion(k1=k1)
    x, y, _ = _wide_list(6, sigma_px=0.1, max_mag=7.0, camera=camera, min_cos=0.5)
    assert x.size == before[1]
    solution = solve_stars(x, y, width=camera.width, height=camera.height)
    assert solution.status is Status.OK, solution.reason
    assert len(solution.matches.hip) >= 0.95 * x.size, (len(solution.matches.hip), x.size)
    assert solution.camera.k1 == pytest.approx(k1, abs=0.005)  # unitless
    assert abs(solution.camera.k2) < 0.005  # unitless; the lens has none
