"""FITS WCS (TAN-SIP) export: read back by astropy, FITS pixel conventions, solved images."""

import numpy as np
import pytest
from astropy.coordinates import SkyCoord

from startrack.camera import Camera, get_preset
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, radec_to_vector, random_rotations, rotation_from_radec_roll
from startrack.io._wcs import fit_sip, read_wcs, solution_wcs, wcs_header, write_wcs
from startrack.solve import solve_image
from startrack.units import ARCSEC, DEG, PIXEL


def _sky_vectors(wcs, x, y):
    sky = wcs.pixel_to_world(x, y)
    return radec_to_vector(sky.ra.rad, sky.dec.rad)


def _random_pixels(camera, n=3000, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-0.5, camera.width - 0.5, n), rng.uniform(-0.5, camera.height - 0.5, n)


@pytest.mark.parametrize("preset", ["aptina-mt9p031", "droid-x2"])
def test_astropy_reads_our_sip_wcs_and_agrees_with_the_camera_model(preset):
    """The Fowler 2013 lenses (60 and 36 px of distortion at the corners) to 0.02 px everywhere."""
    camera, rot = get_preset(preset), random_rotations(None, rng=5)
    wcs = solution_wcs(rot, camera)
    assert wcs.sip is not None
    x, y = _random_pixels(camera)
    ours = rot.inv().apply(camera.pixel_to_vector(x, y))
    err_px = angle_between(_sky_vectors(wcs, x, y), ours) * camera.fx
    assert np.max(err_px) < 0.02 * PIXEL
    back_x, back_y = wcs.world_to_pixel(wcs.pixel_to_world(x, y))
    assert np.max(np.hypot(back_x - x, back_y - y)) < 0.001 * PIXEL


def test_pinhole_wcs_is_plain_tan_with_fits_1_based_crpix_and_the_documented_cd():
    """conventions.md: CD = s [[-cos r, sin r], [-sin r, -cos r]], CRPIX = centre + 1."""
    camera = Camera.from_fov(800, 600, 12.0)
    roll = 25.0 * DEG
    rot = rotation_from_radec_roll(40.0 * DEG, -20.0 * DEG, roll)
    hdr = wcs_header(rot, camera)
    assert hdr["CTYPE1"] == "RA---TAN" and "A_ORDER" not in hdr
    assert (hdr["CRPIX1"], hdr["CRPIX2"]) == (pytest.approx(400.5), pytest.approx(300.5))
    assert (hdr["CRVAL1"], hdr["CRVAL2"]) == (pytest.approx(40.0), pytest.approx(-20.0))
    s = np.degrees(1.0 / camera.fx)
    expected = s * np.array([[-np.cos(roll), np.sin(roll)], [-np.sin(roll), -np.cos(roll)]])
    np.testing.assert_allclose([[hdr["CD1_1"], hdr["CD1_2"]], [hdr["CD2_1"], hdr["CD2_2"]]], expected, atol=1e-12)
    wcs = solution_wcs(rot, camera)
    for x, y in [(0.0, 0.0), (camera.cx, camera.cy), (799.0, 17.0)]:
        ours = rot.inv().apply(camera.pixel_to_vector(x, y))
        assert angle_between(_sky_vectors(wcs, x, y), ours) < 1e-6 * ARCSEC


def test_off_centre_principal_point_and_tangential_terms():
    camera = Camera(width=640, height=480, fx=900.0, fy=905.0, cx=300.2, cy=250.7, k1=-0.2, k2=0.05,
                    p1=0.001, p2=-0.0005)
    rot = random_rotations(None, rng=8)
    wcs = solution_wcs(rot, camera)
    x, y = _random_pixels(camera, seed=2)
    err_px = angle_between(_sky_vectors(wcs, x, y), rot.inv().apply(camera.pixel_to_vector(x, y))) * camera.fx
    assert np.max(err_px) < 0.02 * PIXEL
    assert fit_sip(camera).max_residual_px < 0.01 * PIXEL


def test_write_and_read_a_wcs_file(tmp_path):
    camera, rot = get_preset("aptina-mt9p031"), random_rotations(None, rng=9)
    path = write_wcs(tmp_path / "frame.wcs", rot, camera, date_obs="2012-10-05T03:30:00")
    wcs = read_wcs(path)
    x, y = _random_pixels(camera, 50)
    assert np.max(angle_between(_sky_vectors(wcs, x, y), rot.inv().apply(camera.pixel_to_vector(x, y)))) \
        < 0.02 / camera.fx
    assert wcs.wcs.dateobs.startswith("2012-10-05")


def test_a_wcs_of_a_solved_image_maps_the_matched_stars_to_the_catalog_within_the_residuals():
    from startrack.simulate import get_sensor_preset, simulate_frame

    camera = Camera.from_fov(1024, 1024, 15.0).with_distortion(k1=-0.08)
    truth = rotation_from_radec_roll(83.6 * DEG, 22.0 * DEG, 30.0 * DEG)
    sim = simulate_frame(camera, truth, max_mag=7.5, sensor=get_sensor_preset("generic-cmos"), rng=4)
    solution = solve_image(sim.image, camera=camera)
    assert solution.solved
    wcs = solution_wcs(solution.rot_cam_from_icrs, solution.camera)
    det = solution.detections
    i = solution.matches.det_index
    sky_err = angle_between(_sky_vectors(wcs, det.x[i], det.y[i]), solution.matches.cat_vectors) / ARCSEC
    pixel_arcsec = camera.pixel_scale_arcsec
    np.testing.assert_allclose(sky_err, solution.residuals_arcsec, atol=0.01 * pixel_arcsec)  # the SIP fit
    assert np.sqrt(np.mean(sky_err**2)) < 1.01 * np.sqrt(np.mean(solution.residuals_arcsec**2))
    cat = SkyCoord(*[np.degrees(a) for a in _radec(solution.matches.cat_vectors)], unit="deg")
    px, py = wcs.world_to_pixel(cat)
    np.testing.assert_allclose(np.hypot(px - det.x[i], py - det.y[i]) * pixel_arcsec,
                               solution.residuals_arcsec, atol=0.02 * pixel_arcsec)


def _radec(v):
    from startrack.frames import vector_to_radec

    return vector_to_radec(v)


def test_bad_rotation_is_refused():
    with pytest.raises(InvalidInputError, match="rot_cam_from_icrs"):
        wcs_header(random_rotations(2, rng=1), Camera.from_fov(100, 100, 10.0))
