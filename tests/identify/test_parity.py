"""Mirror images of the sky (:mod:`startrack.identify._parity`): the mirrored camera, the checks,
and solves of flipped real photos and of mirrored star lists."""

from __future__ import annotations

import contextlib
import io
import json
import time

import numpy as np
import pytest
from astropy.wcs import WCS
from PIL import Image
from scipy.spatial.transform import Rotation

from startrack.analysis._starlists import Conditions, generate_star_lists
from startrack.camera import Camera
from startrack.cli import main
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, radec_to_vector
from startrack.identify import MatcherOptions, check_parity
from startrack.io import write_png
from startrack.io._wcs import wcs_header
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.solve import solve_image, solve_stars
from startrack.units import ARCSEC, DEG

CAMERA = Camera(800, 600, 900.0, cx=410.0, cy=290.0, k1=-0.04, p1=0.001)


def test_mirror_image_flips_the_columns_and_twice_is_the_camera():
    mirror = CAMERA.mirror_image()
    assert mirror.mirrored and mirror.cx == 799 - CAMERA.cx and mirror.mirror_image() == CAMERA
    x, y = np.array([3.0, 400.0, 790.0]), np.array([5.0, 300.0, 590.0])
    v = CAMERA.pixel_to_vector(x, y)
    mx, my = mirror.vector_to_pixel(v)
    np.testing.assert_allclose(mx, 799 - x, atol=1e-6)  # px
    np.testing.assert_allclose(my, y, atol=1e-6)  # px
    np.testing.assert_allclose(mirror.pixel_to_vector(799 - x, y), v, atol=1e-12)  # unit vector components


def test_mirrored_jacobian_is_the_derivative():
    mirror = CAMERA.mirror_image()
    v = np.array([[0.1, -0.05, 1.0], [-0.2, 0.15, 1.0]])
    x, y, jac = mirror.project_with_jacobian(v)
    step = 1e-7
    for k in range(3):
        dv = np.zeros(3)
        dv[k] = step
        x2, y2 = mirror.vector_to_pixel(v + dv)
        np.testing.assert_allclose(jac[:, 0, k], (x2 - x) / step, rtol=1e-4)
        np.testing.assert_allclose(jac[:, 1, k], (y2 - y) / step, rtol=1e-4)


def test_mirrored_camera_wcs_maps_pixels_to_the_sky():
    mirror, rot = CAMERA.mirror_image(), Rotation.random(random_state=2)
    wcs = WCS(wcs_header(rot, mirror))
    x, y = np.array([10.0, 400.0, 780.0]), np.array([15.0, 300.0, 580.0])
    ra, dec = wcs.pixel_to_world_values(x, y)
    truth = rot.inv().apply(mirror.pixel_to_vector(x, y))
    sip_accuracy = 0.01 * mirror.pixel_scale_arcsec * ARCSEC  # rad: 0.01 px, what the SIP fit is asked for
    assert np.all(angle_between(radec_to_vector(np.radians(ra), np.radians(dec)), truth) < sip_accuracy)
    assert np.linalg.det(wcs.wcs.cd) < 0  # a camera's own image has a positive determinant


def test_parity_checks_name_the_problem():
    with pytest.raises(InvalidInputError, match="parity must be one of 'normal', 'mirrored', 'either'"):
        check_parity("flipped", None, "normal")
    with pytest.raises(InvalidInputError, match="the camera is mirrored"):
        check_parity("normal", CAMERA.mirror_image(), "either")
    parity, plain = check_parity(None, CAMERA.mirror_image(), "either")  # the camera fixes it
    assert parity == "mirrored" and not plain.mirrored and plain.cx == CAMERA.mirror_image().cx
    assert check_parity(None, CAMERA, "either") == ("normal", CAMERA)
    assert check_parity(None, None, "either") == ("either", None)
    with pytest.raises(InvalidInputError, match="needs method 'quads'"):
        solve_stars(np.arange(5.0), np.arange(5.0) * 2, width=100, height=100, fov_deg=10.0, method="pyramid",
                    parity="either")


@pytest.fixture(scope="module")
def flipped(realdata_dir):
    """crappy.jpg (10 deg, 12 matched stars) flipped left to right, as a grey array."""
    image = np.asarray(Image.open(realdata_dir / "smroid-cedar-solve" / "crappy.jpg").convert("L"), dtype=np.float32)
    return image[:, ::-1].copy()


def _centre_error_px(solution, row) -> float:
    width, height = int(row["width"]), int(row["height"])
    centre = solution.rot_cam_from_icrs.inv().apply(solution.camera.pixel_to_vector((width - 1) / 2, (height - 1) / 2))
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    return float(angle_between(centre, truth) / (float(row["pixscale_arcsec"]) * ARCSEC))


def test_a_flipped_photo_solves_as_a_mirror_image(flipped, truth_table):
    row = next(r for r in truth_table if r["file"] == "crappy.jpg")
    solution = solve_image(flipped)
    assert solution.solved, solution.reason
    assert solution.camera.mirrored
    assert _centre_error_px(solution, row) < 2.0  # the centre does not move when the image is flipped
    det, idx = solution.detections, solution.matches.det_index
    x, y = solution.camera.vector_to_pixel(solution.rot_cam_from_icrs.apply(solution.matches.cat_vectors))
    assert np.median(np.hypot(x - det.x[idx], y - det.y[idx])) < 1.0  # px: the catalog lands on its stars
    wcs = WCS(wcs_header(solution.rot_cam_from_icrs, solution.camera))
    ra, dec = wcs.pixel_to_world_values(det.x[idx], det.y[idx])
    sky = radec_to_vector(np.radians(ra), np.radians(dec))
    assert np.median(angle_between(sky, solution.matches.cat_vectors)) < float(row["pixscale_arcsec"]) * ARCSEC


def test_the_mirrored_camera_of_a_solution_solves_its_image_again(flipped):
    first = solve_image(flipped)
    again = solve_image(flipped, camera=first.camera)  # a mirrored camera fixes the parity
    assert again.solved and again.camera.mirrored, again.reason
    turn = np.degrees((again.rot_cam_from_icrs * first.rot_cam_from_icrs.inv()).magnitude()) * 3600.0
    assert turn < 0.5 * first.camera.pixel_scale_arcsec  # arcsec: half a pixel


def test_a_flipped_photo_is_not_solved_as_given_and_the_time_limit_holds(flipped):
    start = time.perf_counter()
    solution = solve_image(flipped, parity="normal", options=MatcherOptions(timeout_s=1.0))
    assert not solution.solved
    assert time.perf_counter() - start < 4.0  # s: a limit of 1 s, not a batch of candidates past it


def test_mirrored_star_lists_solve_with_their_parity():
    camera = Camera.from_fov(1024, 1024, 15.0)
    stars = generate_star_lists(Conditions(fov_deg=15.0, false_stars_range=(0, 0)), 1, 3)[0]
    x = (camera.width - 1) - stars.x  # the list of the mirror image
    for parity in ("mirrored", "either"):
        solution = solve_stars(x, stars.y, width=1024, height=1024, fov_deg=15.0, parity=parity)
        assert solution.solved and solution.camera.mirrored, parity
        err = angle_between(solution.rot_cam_from_icrs.inv().apply([0, 0, 1.0]),
                            stars.rot_cam_from_icrs.inv().apply([0, 0, 1.0]))
        assert err < 5 * camera.pixel_scale_arcsec * ARCSEC
    plain = solve_stars(x, stars.y, width=1024, height=1024, fov_deg=15.0, options=MatcherOptions(timeout_s=1.0))
    assert not plain.solved  # the default takes the list as given


def test_cli_reports_a_mirror_image(flipped, tmp_path):
    path = tmp_path / "flipped.png"
    write_png(path, np.clip(flipped, 0, 255).astype(np.uint8))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["solve", str(path), "--json"])
    assert code == 0, err.getvalue()
    assert json.loads(out.getvalue())["mirrored"] is True
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        code = main(["solve", str(path), "--parity", "flipped"])
    assert code == 2 and "invalid choice: 'flipped'" in err.getvalue() and "Traceback" not in err.getvalue()


def test_a_flipped_wide_distorted_frame_solves_with_its_lens():
    """A 50 deg frame with barrel distortion (k1 -0.03), flipped: the mirrored solution maps the
    centre and the corners where the true mirrored camera does, within 0.5 px."""
    camera, truth = Camera.from_fov(1640, 1232, 50.0, k1=-0.03), Rotation.random(random_state=1)
    sim = simulate_frame(camera, truth, max_mag=6.5, sensor=get_sensor_preset("generic-cmos"), rng=1)
    solution = solve_image(np.ascontiguousarray(sim.image[:, ::-1]))
    assert solution.solved and solution.camera.mirrored, solution.reason
    x, y = np.array([819.5, 0.0, 1639.0, 0.0, 1639.0]), np.array([615.5, 0.0, 1231.0, 1231.0, 0.0])
    true_sky = truth.inv().apply(camera.mirror_image().pixel_to_vector(x, y))
    solved_sky = solution.rot_cam_from_icrs.inv().apply(solution.camera.pixel_to_vector(x, y))
    pixel_rad = np.radians(50.0) / 1640
    assert np.all(angle_between(true_sky, solved_sky) < 0.5 * pixel_rad)


def test_the_compiled_helpers_take_a_mirrored_camera():
    """pixel_vectors, the matches, the pose fit and the deleted residuals of a mirrored camera on
    the flipped columns are those of the plain camera on the columns as given."""
    from startrack.identify import _refine as refine

    rng = np.random.default_rng(6)
    x, y = rng.uniform(0, 799, 25), rng.uniform(0, 599, 25)
    rot = Rotation.random(random_state=6)
    ref = rot.inv().apply(CAMERA.pixel_to_vector(x, y))
    mirror, xm = CAMERA.mirror_image(), 799 - x
    np.testing.assert_allclose(refine.pixel_vectors(mirror, xm, y), refine.pixel_vectors(CAMERA, x, y), atol=1e-12)
    for match in (refine.match_predicted, refine.predicted_pairs):
        plain, flipped = match(ref, rot.as_matrix(), CAMERA, x, y, 2.0), match(ref, rot.as_matrix(), mirror, xm, y, 2.0)
        for a, b in zip(plain, flipped, strict=True):
            np.testing.assert_allclose(a, b, atol=1e-9)  # indices, and squared distances in px^2
    start = (Rotation.from_rotvec([1e-4, -2e-4, 3e-4]) * rot).as_matrix()
    matrix, camera, residual = refine.fit_pose(start, mirror.with_focal(905.0), ref, xm, y, fit_focal=True)
    assert camera.mirrored and camera.fx == pytest.approx(900.0, rel=1e-6)
    assert np.degrees(Rotation.from_matrix(matrix @ rot.as_matrix().T).magnitude()) < 1e-6  # deg
    assert residual.max() < 1e-6  # px
    np.testing.assert_allclose(refine.leave_one_out_residuals(rot.as_matrix(), mirror, ref, xm, y, fit_focal=True),
                               refine.leave_one_out_residuals(rot.as_matrix(), CAMERA, ref, x, y, fit_focal=True),
                               atol=1e-9)  # px


def test_the_tracking_projection_takes_a_mirrored_camera():
    from startrack.track._windows import project

    mirror = Camera(800, 600, 900.0).mirror_image()
    vectors = np.array([[0.1, -0.2, 0.05], [0.05, 0.1, -0.1], [1.0, 1.0, 1.0]])  # columns (3, K)
    x, y = project(mirror, vectors)
    mx, my = mirror.vector_to_pixel(vectors.T)
    np.testing.assert_allclose(x, mx, atol=1e-9)  # px
    np.testing.assert_allclose(y, my, atol=1e-9)  # px
