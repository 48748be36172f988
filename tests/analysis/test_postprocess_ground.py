"""The ground-photo analyses: attitude error with and without the lens and atmosphere corrections
(against the solver and solve_ground_photo), and fixed-mount repeatability (against
calibrate.repeatability), on simulated frames of a camera fixed to the ground at a real site."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.analysis._records import ImageRecord
from startrack.analysis.postprocess import ResultSet, run_analysis
from startrack.analysis.postprocess._ground import error_arcsec
from startrack.calibrate._ground import rotation_enu_from_icrs
from startrack.calibrate._ground_solve import solve_ground_photo
from startrack.calibrate._repeatability import repeatability
from startrack.calibrate._sites import get_site
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.solve import solve_image
from startrack.units import ARCMIN, ARCSEC, DEG

SITE = get_site("moab-ut")
START = Time("2024-03-10T05:00:00", scale="utc")
LENS = Camera.from_fov(512, 448, 20.0, k1=-0.3, cx=262.0, cy=220.0, name="barrel")
"""A wide barrel lens: about 7 px of distortion in the corners."""
PIXEL_RAD = LENS.pixel_scale_arcsec * ARCSEC


def _mount(altitude_deg: float, azimuth_deg: float, roll_rad: float) -> Rotation:
    """rot_cam_from_enu of a camera pointing at (altitude, azimuth), rolled about its axis."""
    alt, az = altitude_deg * DEG, azimuth_deg * DEG
    axis = [np.sin(az) * np.cos(alt), np.cos(az) * np.cos(alt), np.sin(alt)]
    to_axis, _ = Rotation.align_vectors([[0.0, 0.0, 1.0]], [axis])
    return Rotation.from_rotvec([0.0, 0.0, roll_rad]) * to_axis


MOUNT = _mount(40.0, 120.0, 0.4)


def _frames(n: int, step_min: float):
    """Frames of the fixed camera at START + k step_min: (time, true attitude, image)."""
    sensor = get_sensor_preset("generic-cmos")
    out = []
    for k in range(n):
        when = START + TimeDelta(60.0 * step_min * k, format="sec")
        truth = MOUNT * rotation_enu_from_icrs(when, SITE)
        sim = simulate_frame(LENS, truth, max_mag=6.5, sensor=sensor, epoch_jyear=when, rng=k)
        out.append((when, truth, sim.image))
    return out


@pytest.fixture(scope="module")
def night():
    """Six frames ten minutes apart, solved with the calibrated lens at their epoch."""
    records = []
    for k, (when, truth, image) in enumerate(_frames(6, 10.0)):
        solution = solve_image(image, camera=LENS, epoch=when)
        assert solution.solved, solution.reason
        records.append(ImageRecord(f"n{k}.png", solution, image=image, time=when, camera=LENS,
                                   true_rot_cam_from_icrs=truth))
    return ResultSet("night", tuple(records))


def _rows(table, **where):
    return [i for i in range(len(table["record"])) if all(table[k][i] == v for k, v in where.items())]


def test_lens_on_is_the_solvers_attitude_and_lens_off_leaves_the_distortion_in_the_residuals(night):
    result = run_analysis("corrections", [night])
    table = result.tables["errors"]
    assert set(table["against"]) == {"truth"} and set(table["atmosphere"]) == {False}  # no site: no atmosphere rows
    for record in night.records:
        on, = _rows(table, record=record.name, lens=True)
        off, = _rows(table, record=record.name, lens=False)
        expected = error_arcsec(record.solution.rot_cam_from_icrs, record.true_rot_cam_from_icrs)
        assert table["total_arcsec"][on] == pytest.approx(expected[0], abs=0.01)
        assert table["total_arcsec"][on] < 0.3 * LENS.pixel_scale_arcsec
        rms = np.sqrt(np.mean(record.solution.residuals_arcsec**2))
        assert table["residual_rms_arcsec"][on] == pytest.approx(rms, rel=1e-6)
        assert table["residual_rms_arcsec"][off] > 5 * table["residual_rms_arcsec"][on]
        assert table["n_stars"][on] == len(record.solution.matches)


def test_atmosphere_on_is_what_solve_ground_photo_gives_and_the_rest_is_measured_against_it(night):
    record = replace(night.records[0], true_rot_cam_from_icrs=None)  # a real photo: no truth
    result = run_analysis("corrections", [ResultSet("photo", (record,))], {"site": SITE.name})
    table = result.tables["errors"]
    assert set(table["against"]) == {"lens and atmosphere corrected"} and len(table["record"]) == 4
    both, = _rows(table, lens=True, atmosphere=True)
    plain, = _rows(table, lens=True, atmosphere=False)
    assert table["total_arcsec"][both] == 0.0
    ground = solve_ground_photo(record.image, SITE, time=record.time, camera=LENS).solution
    expected = np.degrees(attitude_error(ground.rot_cam_from_icrs, record.solution.rot_cam_from_icrs)) * 3600
    assert table["total_arcsec"][plain] == pytest.approx(expected, abs=0.01)
    # refraction at 40 deg (1.2') and aberration (< 21") move the attitude by tens of arcsec to minutes
    assert 20.0 < table["total_arcsec"][plain] < 10 * 60.0
    same = run_analysis("corrections", [ResultSet("photo", (replace(record, site=SITE),))]).tables["errors"]
    assert same["total_arcsec"] == table["total_arcsec"]  # the record's own site is used when no parameter names one


def test_a_lens_model_of_another_size_is_refused(night):
    with pytest.raises(InvalidInputError, match="give parameter 'camera' for a preset of that size"):
        run_analysis("corrections", [night], {"camera": "far-mst"})


def test_repeatability_is_calibrate_repeatability_and_finds_the_mount(night):
    result = run_analysis("repeatability", [night], {"site": SITE.name})
    direct = repeatability(Time([r.time.isot for r in night.records], scale="utc"),
                           [r.solution.rot_cam_from_icrs for r in night.records], SITE)
    images = result.tables["images"]
    np.testing.assert_allclose(images["total_arcmin"], direct.total_rad / ARCMIN, rtol=1e-9)
    np.testing.assert_allclose(images["roll_arcmin"], direct.roll_rad / ARCMIN, rtol=1e-9)
    np.testing.assert_allclose(images["minutes"], [0, 10, 20, 30, 40, 50], atol=1e-6)
    mount = result.tables["mount"]
    found = Rotation.from_quat([mount[k][0] for k in ("qx", "qy", "qz", "qw")])
    assert attitude_error(direct.mount, found) < 1e-9
    assert attitude_error(MOUNT, found) < 0.2 * PIXEL_RAD  # six solves of a fraction of a pixel each
    assert mount["boresight_altitude_deg"][0] == pytest.approx(40.0, abs=0.01)
    assert mount["boresight_azimuth_deg"][0] == pytest.approx(120.0, abs=0.01)
    assert result.summary["mount standard error, arcmin"] == pytest.approx(direct.mount_standard_error_rad / ARCMIN)
    by_coordinates = run_analysis("repeatability", [night], {"latitude_deg": SITE.latitude_deg,
                                                             "longitude_deg": SITE.longitude_deg})
    # the height changes nothing here: the ENU axes depend on latitude and longitude only
    assert by_coordinates.tables["images"]["total_arcmin"] == images["total_arcmin"]


def test_repeatability_refuses_without_a_site_or_without_two_timed_images(night):
    with pytest.raises(InvalidInputError, match="give parameter 'site'"):
        run_analysis("repeatability", [night])
    untimed = ResultSet("untimed", tuple(replace(r, time=None) for r in night.records[1:]) + night.records[:1])
    with pytest.raises(InvalidInputError, match="has 1 .5 solved without a time"):
        run_analysis("repeatability", [untimed], {"site": SITE.name})
    with pytest.raises(InvalidInputError, match="not both"):
        run_analysis("repeatability", [night], {"site": SITE.name, "latitude_deg": 1.0, "longitude_deg": 2.0})
    with pytest.raises(InvalidInputError, match="known sites"):
        run_analysis("repeatability", [night], {"site": "atlantis"})
