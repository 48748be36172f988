"""The field of view an image's header states (:mod:`startrack.identify._image_fov`), and the
solve that searches it first when the default search does not reach it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import startrack.solve as solve_module
from startrack import AttitudeSolution, Camera, Status, solve_image, solve_stars
from startrack.frames import attitude_error, rotation_from_radec_roll
from startrack.identify import stated_fov_deg, stated_search_range
from startrack.io import Image
from startrack.simulate import get_sensor_preset, random_attitude, simulate_frame
from startrack.solve import WIDE_RETRY_FOV_RANGE_DEG, _fov_searches
from startrack.units import ARCSEC


def _deg_atan2(opposite: float, adjacent: float) -> float:
    return math.degrees(2.0 * math.atan(opposite / adjacent))


@pytest.mark.parametrize("focal_35mm", [12, 14, 24, 50, 200])
def test_a_3_to_2_photo_spans_a_full_frame_cameras_width_at_its_35mm_focal_length(focal_35mm):
    """A 3:2 image has the full frame's shape: its width is the 36 mm frame's whatever the scaling."""
    fov = stated_fov_deg({"FocalLengthIn35mmFilm": focal_35mm}, 6000, 4000)
    assert fov == pytest.approx(_deg_atan2(18.0, focal_35mm), abs=1e-9)  # deg


def test_a_portrait_photo_takes_the_same_diagonal_with_its_own_width():
    landscape = stated_fov_deg({"FocalLengthIn35mmFilm": 26}, 4032, 3024)
    portrait = stated_fov_deg({"FocalLengthIn35mmFilm": 26}, 3024, 4032)
    diagonal = math.atan(math.hypot(36.0, 24.0) / 52.0)
    assert landscape == pytest.approx(math.degrees(2 * math.atan(math.tan(diagonal) * 0.8)), abs=1e-9)
    assert portrait == pytest.approx(math.degrees(2 * math.atan(math.tan(diagonal) * 0.6)), abs=1e-9)


def test_the_focal_plane_resolution_gives_the_sensor_when_there_is_no_35mm_focal_length():
    """An APS-C sensor of 23.5 x 15.6 mm behind a 10 mm lens, its resolution in pixels per inch."""
    header = {"FocalLength": 10.0, "ExifImageWidth": 6000, "ExifImageHeight": 4000, "FocalPlaneResolutionUnit": 2,
              "FocalPlaneXResolution": 6000 / (23.5 / 25.4), "FocalPlaneYResolution": 4000 / (15.6 / 25.4)}
    diagonal_tan = math.hypot(23.5, 15.6) / 20.0
    expected = math.degrees(2 * math.atan(diagonal_tan * 6000 / math.hypot(6000, 4000)))
    assert stated_fov_deg(header, 6000, 4000) == pytest.approx(expected, abs=1e-9)  # deg, 99.0


def test_a_fits_header_gives_a_telescopes_field_from_its_focal_length_and_pixel_size():
    header = {"FOCALLEN": 500.0, "XPIXSZ": 3.76}  # a 500 mm refractor, a 3.76 um camera
    fov = stated_fov_deg(header, 6248, 4176)
    assert fov == pytest.approx(_deg_atan2(6248 * 3.76e-3 / 2, 500.0), abs=1e-9)  # deg, 2.69: below the default
    assert stated_search_range(header, 6248, 4176) == pytest.approx((0.9 * fov, 1.1 * fov), abs=1e-12)  # deg


@pytest.mark.parametrize("fov_deg", [1.2, 2.5, 20.0, 120.0])
@pytest.mark.parametrize("roll_deg", [0.0, 30.0, 135.0])
def test_a_celestial_wcs_states_its_field_through_its_scale(fov_deg, roll_deg):
    """Our own WCS of a pinhole camera, at any roll: its scale gives back the camera's field."""
    from startrack.io import wcs_header

    camera = Camera.from_fov(3000, 2000, fov_deg)
    attitude = rotation_from_radec_roll(math.radians(210.0), math.radians(-35.0), math.radians(roll_deg))
    header = dict(wcs_header(attitude, camera))
    assert stated_fov_deg(header, 3000, 2000) == pytest.approx(fov_deg, rel=1e-9)


def test_a_wcs_of_cdelt_and_pc_and_its_precedence_over_the_focal_length():
    scale = 1.5 / 3600  # deg per px
    cos, sin = math.cos(math.radians(40.0)), math.sin(math.radians(40.0))
    header = {"CTYPE1": "RA---TAN", "CDELT1": -scale, "CDELT2": scale, "PC1_1": cos, "PC2_1": sin}
    expected = _deg_atan2(4000 * math.radians(scale) / 2, 1.0)  # deg, 1.67
    assert stated_fov_deg(header, 4000, 3000) == pytest.approx(expected, rel=1e-12)
    assert stated_fov_deg({"CTYPE1": "RA---TAN", "CDELT1": -scale}, 4000, 3000) == pytest.approx(expected, rel=1e-12)
    transposed = {"CTYPE1": "DEC--TAN", "CTYPE2": "RA---TAN", "CD1_1": 0.0, "CD2_1": scale}  # deg per px
    assert stated_fov_deg(transposed, 4000, 3000) == pytest.approx(expected, rel=1e-12)
    nominal = {"FOCALLEN": 400.0, "XPIXSZ": 3.76}  # 2.15 deg: a WCS measured on the sky comes first
    assert stated_fov_deg({**nominal, **header}, 4000, 3000) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("header", [
    {"CTYPE1": "PIXEL", "CD1_1": 1.0, "CD2_1": 0.0},  # not on the sky
    {"CTYPE1": "RA---TAN", "CD1_1": "x", "CD2_1": 0.0},
    {"CTYPE1": "RA---TAN", "CD1_1": float("nan"), "CD2_1": 0.0},
    {"CTYPE1": "RA---TAN", "CD1_1": 0.0, "CD2_1": 0.0},
    {"CTYPE1": "RA---TAN", "CDELT1": True},
    {"CTYPE1": "RA---TAN"},
    {"CTYPE1": 3, "CDELT1": 0.001},
    {"CDELT1": 0.001},
])
def test_a_wcs_that_gives_no_scale_on_the_sky_is_passed_over(header):
    assert stated_fov_deg(header, 4000, 3000) is None


@pytest.mark.parametrize("value", ["x", -14, 0, None, True, float("nan"), float("inf"), [14]])
def test_a_focal_length_that_is_not_a_positive_number_is_passed_over(value):
    assert stated_fov_deg({"FocalLengthIn35mmFilm": value}, 6000, 4000) is None
    assert stated_fov_deg({"FOCALLEN": value, "XPIXSZ": 3.76}, 6000, 4000) is None


@pytest.mark.parametrize("unit", [[2], "inch", None, 1, 7])
def test_a_focal_plane_unit_that_is_not_one_of_exifs_is_passed_over(unit):
    """1 is EXIF's "no unit"; before, a list (a header a caller built) raised TypeError (unhashable)."""
    header = {"FocalLength": 10.0, "ExifImageWidth": 6000, "ExifImageHeight": 4000,
              "FocalPlaneXResolution": 6485.1, "FocalPlaneYResolution": 6512.8, "FocalPlaneResolutionUnit": unit}
    assert stated_fov_deg(header, 6000, 4000) is None


def test_a_field_outside_what_a_solve_takes_is_no_statement():
    assert stated_fov_deg({"FocalLengthIn35mmFilm": 5}, 6000, 4000) == pytest.approx(148.95, abs=0.01)  # deg: kept
    assert stated_fov_deg({"FocalLengthIn35mmFilm": 4}, 6000, 4000) is None  # 154.9 deg, past the widest
    assert stated_fov_deg({}, 6000, 4000) is None and stated_fov_deg(None, 6000, 4000) is None


def test_only_a_field_beyond_the_default_search_is_searched_first():
    """An ultra-wide lens's range reaches from the wide fields' database's start (a crop narrows
    the field) to 10 % past the stated field; a field the default search covers changes nothing."""
    assert stated_search_range({"FocalLengthIn35mmFilm": 14}, 6000, 4000) == pytest.approx(
        (70.0, 1.1 * _deg_atan2(18.0, 14.0)))
    assert stated_search_range({"FocalLengthIn35mmFilm": 24}, 6000, 4000) is None


CAMERA = Camera.from_fov(1500, 1000, 110.0).with_distortion(k1=-0.005)
"""An ultra-wide 3:2 lens: EXIF would state a 35 mm focal length of 18 / tan(55 deg) = 12.6 mm."""


def _simulated(camera: Camera, seed: int):
    """A simulated frame (V <= 6, the generic CMOS sensor) at a random attitude, and the attitude."""
    truth = random_attitude(np.random.default_rng(seed))
    return simulate_frame(camera, truth, max_mag=6.0, sensor=get_sensor_preset("generic-cmos"), rng=seed), truth


def _frame(camera: Camera, seed: int):
    """The pixels of :func:`_simulated`'s frame and its attitude."""
    sim, truth = _simulated(camera, seed)
    return sim.image, truth


@pytest.mark.parametrize("header", [{"FocalLengthIn35mmFilm": 18.0 / math.tan(math.radians(55.0))}, {}])
def test_an_ultra_wide_photo_solves_with_no_field_given(header):
    """Before: with no field given, the default search (to 100 deg) could not solve it. With its EXIF
    focal length the stated field is searched first; without, the wide fields after the default."""
    data, truth = _frame(CAMERA, 3)
    solution = solve_image(Image(data=data, header=header))
    assert solution.status is Status.OK, solution.reason
    assert attitude_error(solution.rot_cam_from_icrs, truth) < CAMERA.pixel_scale_arcsec * ARCSEC  # a pixel
    assert solution.fov_source == ("header" if header else "wide")


@pytest.mark.parametrize(("given", "source"), [({}, "default"), ({"fov_deg": 40.0}, "given"),
                                               ({"fov_range_deg": (30.0, 50.0)}, "given"),
                                               ({"camera": True}, "camera")])
def test_a_solve_says_which_field_of_view_it_searched(given, source):
    camera = Camera.from_fov(1200, 800, 40.0)
    sim, _ = _simulated(camera, 4)
    given = {"camera": camera} if "camera" in given else given
    assert solve_image(sim.image, **given).fov_source == source
    inside = camera.in_image(sim.truth.x, sim.truth.y)  # the truth lists stars whose light reaches the frame too
    assert solve_stars(sim.truth.x[inside], sim.truth.y[inside], width=camera.width, height=camera.height,
                       **given).fov_source == source


def test_the_fields_searched_in_turn():
    """Given anything about the field: that alone. Else the header's field first when the default
    search does not reach it, then the default; with no such header, the default, then the
    ultra-wide fields (the quads matcher only: the others would build tables for them)."""
    wide = {"FocalLengthIn35mmFilm": 13}  # 108 deg on a 3:2 image
    camera = Camera.from_fov(600, 400, 20.0)
    assert _fov_searches(wide, 600, 400, 20.0, None, None, "quads") == [(None, "given")]
    assert _fov_searches(wide, 600, 400, None, (5.0, 30.0), None, "quads") == [((5.0, 30.0), "given")]
    assert _fov_searches(wide, 600, 400, None, None, camera, "quads") == [(None, "camera")]
    assert _fov_searches(wide, 600, 400, None, None, None, "quads") == [(stated_search_range(wide, 600, 400), "header"),
                                                                        (None, "default")]
    assert _fov_searches({}, 600, 400, None, None, None, "quads") == [(None, "default"),
                                                                      (WIDE_RETRY_FOV_RANGE_DEG, "wide")]
    assert _fov_searches({"FocalLengthIn35mmFilm": 50}, 600, 400, None, None, None, "pyramid") == [(None, "default")]


def test_a_photo_that_matches_nothing_says_which_fields_were_searched():
    """12 random spots: no match in the default search nor in the ultra-wide one, both named."""
    rng = np.random.default_rng(0)
    rows, cols = np.mgrid[:600, :800]
    data = rng.normal(100.0, 5.0, rows.shape)
    for x, y in rng.uniform([30, 20], [770, 580], (12, 2)):
        data += 500.0 * np.exp(-((cols - x) ** 2 + (rows - y) ** 2) / 4.0)
    solution = solve_image(data)
    assert solution.status is Status.NO_MATCH
    assert solution.reason.endswith("(fields of view searched: 3-100 deg, then 90-150 deg)"), solution.reason


def test_a_photo_whose_exif_states_a_wider_field_than_its_own_falls_back_on_the_default_search():
    """A crop keeps its camera's EXIF: the stated range fails, the default search solves it."""
    camera = Camera.from_fov(1200, 800, 40.0)
    data, truth = _frame(camera, 4)
    solution = solve_image(Image(data=data, header={"FocalLengthIn35mmFilm": 13}))
    assert solution.status is Status.OK, solution.reason
    assert attitude_error(solution.rot_cam_from_icrs, truth) < camera.pixel_scale_arcsec * ARCSEC


@pytest.mark.parametrize(("wide_status", "note"), [
    (Status.TIMEOUT, "3-100 deg (out of time), then 90-150 deg (out of time)"),
    (Status.NO_MATCH, "3-100 deg (out of time), then 90-150 deg"),
])
def test_a_default_search_that_runs_out_of_time_is_followed_by_the_wide_one(monkeypatch, wide_status, note):
    """The default search of an ultra-wide frame took 2.8 s here, past its 5 s limit when the
    machine was busy: a timeout, like no match, leads to the next range (not a too-few-stars), and
    a failure after it is a timeout (that range was not searched through) saying which ran out."""
    searched = []

    def run(request, method, options, fov_source):
        searched.append(request.fov_range_deg)
        status = Status.TIMEOUT if len(searched) == 1 else wide_status
        return AttitudeSolution(status=status, reason="nothing", solve_time_s=0.5)

    monkeypatch.setattr(solve_module, "_run", run)
    camera = Camera.from_fov(600, 400, 40.0)
    data, _ = _frame(camera, 4)
    solution = solve_image(data)
    assert searched == [(3.0, 100.0), WIDE_RETRY_FOV_RANGE_DEG]
    assert solution.status is Status.TIMEOUT and solution.solve_time_s >= 1.0  # s: both attempts, and detection
    assert solution.reason == f"nothing (fields of view searched: {note})"
