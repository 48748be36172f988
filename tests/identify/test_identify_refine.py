"""The pose fit of the final stage: Gauss-Newton on rotation matrices, its Jacobian, and the re-match.

The fit and the re-match of :mod:`startrack.identify._final_fit` are written for speed (a few
fused numpy operations per step, a cell filter in front of the nearest-star match); these tests
pin them to what they replace: finite differences, scipy's rotations and a match over every
predicted star.
"""

import subprocess
import sys

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.frames import attitude_error
from startrack.identify import _final_fit as final_fit
from startrack.identify import _refine as refine
from startrack.units import ARCSEC, PIXEL

DISTORTED = Camera(width=1600, height=1200, fx=1400.0, fy=1390.0, cx=810.0, cy=590.0,
                   k1=-0.12, k2=0.03, p1=4e-4, p2=-3e-4)


def _field(camera: Camera, n: int, seed: int):
    """A random attitude and n stars spread over the image: (rotation, ICRS unit vectors (n, 3), x, y)."""
    rng = np.random.default_rng(seed)
    rot = Rotation.random(random_state=seed)
    x, y = rng.uniform(20, camera.width - 20, n), rng.uniform(20, camera.height - 20, n)
    return rot, rot.inv().apply(camera.pixel_to_vector(x, y)), x, y


def _pixels(matrix, camera, ref):
    """Predicted pixels (x, y) of ICRS vectors for an attitude matrix."""
    return camera.vector_to_pixel(ref @ matrix.T)


@pytest.mark.parametrize("camera", [Camera.from_fov(1024, 1024, 10.0), DISTORTED], ids=["pinhole", "distorted"])
def test_jacobian_matches_finite_differences(camera):
    rot, ref, x, y = _field(camera, 12, seed=1)
    matrix = (Rotation.from_rotvec([2e-3, -1e-3, 3e-3]) * rot).as_matrix()  # not at the optimum
    offset = np.array([x - camera.cx, y - camera.cy])
    focal = np.array([[camera.fx], [camera.fy]])
    free = refine.free_flags(fit_focal=True, fit_aspect=True, fit_k1=True, fit_k2=True)
    system = refine._system(camera, focal, matrix @ ref.T, offset, free)
    assert np.allclose(system[-1], np.concatenate([x, y]) - np.concatenate(_pixels(matrix, camera, ref)),
                       atol=1e-9 * PIXEL)

    def predicted(params):
        turned = Rotation.from_rotvec(params[:3]).as_matrix() @ matrix
        moved = camera.with_focal(camera.fx * np.exp(params[3]), camera.fy * np.exp(params[3] + params[4]))
        moved = moved.with_distortion(k1=camera.k1 + params[5], k2=camera.k2 + params[6])
        return np.concatenate(_pixels(turned, moved, ref))

    step = 1e-7
    for k in range(7):
        delta = np.zeros(7)
        delta[k] = step
        numeric = (predicted(delta) - predicted(-delta)) / (2 * step)
        assert np.allclose(system[k], numeric, rtol=1e-5, atol=1e-4 * PIXEL), k


def test_fit_recovers_attitude_focal_and_k1_of_a_distorted_camera():
    rot, ref, x, y = _field(DISTORTED, 30, seed=2)
    start = (Rotation.from_rotvec([0.0, 0.0, 0.01]) * rot).as_matrix()  # 0.6 deg about the boresight
    guess = DISTORTED.with_focal(1.02 * DISTORTED.fx, 1.02 * DISTORTED.fy).with_distortion(k1=0.0)
    matrix, camera, residual = refine.fit_pose(start, guess, ref, x, y, fit_focal=True, fit_k1=True)
    assert attitude_error(Rotation.from_matrix(matrix), rot) < 1e-4 * ARCSEC
    assert camera.fx == pytest.approx(DISTORTED.fx, rel=1e-9)
    assert camera.fy == pytest.approx(DISTORTED.fy, rel=1e-9)
    assert camera.k1 == pytest.approx(DISTORTED.k1, abs=1e-9)
    assert np.max(residual) < 1e-6 * PIXEL


def test_fit_recovers_pixel_aspect_and_k2_from_a_square_pixel_guess():
    """A guess with square pixels and no k2 (the start of a solve of an uncalibrated sensor with
    rectangular pixels and a wide lens) converges to the true fy / fx and k2."""
    camera = Camera(width=1600, height=1200, fx=900.0, fy=900.0 / 1.9, k1=-0.08, k2=0.02)
    rot, ref, x, y = _field(camera, 40, seed=5)
    guess = camera.with_focal(camera.fx, camera.fx * 0.97 / 1.9).with_distortion(k1=0.0, k2=0.0)
    matrix, fitted, residual = refine.fit_pose(rot.as_matrix(), guess, ref, x, y, fit_focal=True, fit_k1=True,
                                               fit_aspect=True, fit_k2=True)
    assert fitted.fy / fitted.fx == pytest.approx(1 / 1.9, rel=1e-9)
    assert (fitted.k1, fitted.k2) == pytest.approx((-0.08, 0.02), abs=1e-9)
    assert np.max(residual) < 1e-6 * PIXEL
    too_few = refine.fit_pose(rot.as_matrix(), guess, ref[:5], x[:5], y[:5], fit_focal=True, fit_aspect=True)[1]
    assert too_few.fy / too_few.fx == pytest.approx(guess.fy / guess.fx, rel=1e-12)  # 5 stars: aspect stays


def test_fixed_focal_stays_fixed_and_refine_pointing_is_the_same_fit():
    camera = Camera.from_fov(1024, 768, 12.0)
    rot, ref, x, y = _field(camera, 9, seed=3)
    x = x + np.random.default_rng(4).normal(0, 0.3, 9)
    start = Rotation.from_rotvec([1e-3, 2e-3, -1e-3]) * rot
    matrix, fitted, res = refine.fit_pose(start.as_matrix(), camera, ref, x, y, fit_focal=False)
    assert fitted == camera
    assert np.allclose(res, np.hypot(*(np.array(_pixels(matrix, camera, ref)) - [x, y])), atol=1e-9 * PIXEL)
    r2, c2, res2 = refine.refine_pointing(start, camera, ref, x, y, fit_focal=False)
    assert attitude_error(r2, Rotation.from_matrix(matrix)) < 1e-9 * ARCSEC
    assert c2 == camera
    assert np.array_equal(res2, res)


@pytest.mark.parametrize("angle", [1e-10, 1e-6, 0.3, 2.0, 3.1])
def test_turn_between_matrices_matches_scipy(angle):
    a = Rotation.random(random_state=5)
    b = Rotation.from_rotvec(angle * np.array([0.6, -0.8, 0.0])) * a
    expected = (a * b.inv()).magnitude()
    assert final_fit._turn_rad(a.as_matrix(), b.as_matrix()) == pytest.approx(expected, rel=1e-9, abs=1e-15)


def _scipy_fit(start, camera, ref, x, y, fit_focal, fit_k1):
    """The same least-squares problem solved by scipy (Levenberg-Marquardt on finite differences
    of the camera's own projection): (matrix (3, 3), camera)."""
    def fitted(params):
        moved = camera
        if fit_focal:
            moved = moved.with_focal(camera.fx * np.exp(params[3]), camera.fy * np.exp(params[3]))
        if fit_k1:
            moved = moved.with_distortion(k1=params[4])
        return Rotation.from_rotvec(params[:3]).as_matrix() @ start, moved

    def residuals(params):
        return np.concatenate(_pixels(*fitted(params), ref)) - np.concatenate([x, y])

    guess = np.zeros(3 + int(fit_focal) + int(fit_k1))
    if fit_k1:
        guess[4] = camera.k1
    solution = least_squares(residuals, guess, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, x_scale="jac")
    return fitted(solution.x)


@pytest.mark.parametrize(("fit_focal", "fit_k1"), [(False, False), (True, False), (True, True)])
def test_fit_equals_scipy_least_squares_on_a_distorted_camera(fit_focal, fit_k1):
    """Noisy stars (the optimum has residuals), a start 0.2 deg and 2 % off: same optimum as scipy."""
    rot, ref, x, y = _field(DISTORTED, 30, seed=7)
    noise = np.random.default_rng(8).normal(0, 0.4, (2, 30))
    x, y = x + noise[0], y + noise[1]
    start = (Rotation.from_rotvec([2e-3, -3e-3, 1e-3]) * rot).as_matrix()
    guess = DISTORTED.with_focal(1.02 * DISTORTED.fx, 1.02 * DISTORTED.fy) if fit_focal else DISTORTED
    guess = guess.with_distortion(k1=-0.1) if fit_k1 else guess
    matrix, camera, residual = refine.fit_pose(start, guess, ref, x, y, fit_focal=fit_focal, fit_k1=fit_k1)
    want_matrix, want_camera = _scipy_fit(start, guess, ref, x, y, fit_focal, fit_k1)
    assert attitude_error(Rotation.from_matrix(matrix), Rotation.from_matrix(want_matrix)) < 0.01 * ARCSEC
    px, py = _pixels(matrix, camera, ref)
    want_px, want_py = _pixels(want_matrix, want_camera, ref)
    assert np.max(np.hypot(px - want_px, py - want_py)) < 1e-6 * PIXEL
    assert np.allclose(residual, np.hypot(want_px - x, want_py - y), atol=1e-6 * PIXEL)
    assert camera.fx == pytest.approx(want_camera.fx, rel=1e-9)
    assert camera.fy / camera.fx == pytest.approx(guess.fy / guess.fx, rel=1e-12)  # fx and fy scale together
    assert camera.k1 == pytest.approx(want_camera.k1, abs=1e-9)
    assert (camera.k2, camera.p1, camera.p2, camera.cx) == (guess.k2, guess.p1, guess.p2, guess.cx)


def test_deleted_residuals_of_a_distorted_camera_match_refits_without_each_star():
    rot, ref, x, y = _field(DISTORTED, 10, seed=9)
    noise = np.random.default_rng(10).normal(0, 0.3, (2, 10))
    x, y = x + noise[0], y + noise[1]
    x[3] += 5.0  # one wrong association
    matrix, camera, _ = refine.fit_pose(rot.as_matrix(), DISTORTED, ref, x, y, fit_focal=True)
    deleted = refine.leave_one_out_residuals(matrix, camera, ref, x, y, fit_focal=True)
    for k in range(10):
        keep = np.arange(10) != k
        m, c, _ = refine.fit_pose(matrix, camera, ref[keep], x[keep], y[keep], fit_focal=True)
        px, py = _pixels(m, c, ref[k:k + 1])
        assert deleted[k] == pytest.approx(np.hypot(px[0] - x[k], py[0] - y[k]), abs=0.05 * PIXEL)
    assert np.argmax(deleted) == 3


SINGULAR = {  # pixel positions (x, y) and whether the focal length is free
    "no stars": ([], [], False),
    "one star": ([300.0], [400.0], False),
    "one star at the principal point": ([511.5], [511.5], False),
    "two stars, focal free": ([300.0, 700.0], [400.0, 650.0], True),
    "three stars on one pixel, focal free": ([300.0] * 3, [400.0] * 3, True),
    "collinear through the principal point, focal free": ([100.0, 511.5, 900.0], [511.5] * 3, True),
}


@pytest.mark.parametrize("case", SINGULAR.values(), ids=SINGULAR.keys())
def test_too_few_stars_give_a_finite_fit_near_the_start(case):
    """Normal equations singular (or nearly): the least-squares step, not one along the null space."""
    camera = Camera.from_fov(1024, 1024, 10.0)
    x, y = np.array(case[0]), np.array(case[1])
    rot = Rotation.random(random_state=11)
    ref = rot.inv().apply(camera.pixel_to_vector(x, y)).reshape(-1, 3)
    start = Rotation.from_rotvec([1e-3, -2e-3, 3e-3]) * rot
    matrix, fitted, residual = refine.fit_pose(start.as_matrix(), camera, ref, x + 0.3, y - 0.2, fit_focal=case[2])
    assert np.allclose(matrix @ matrix.T, np.eye(3), atol=1e-12)
    assert attitude_error(Rotation.from_matrix(matrix), rot) <= attitude_error(start, rot) + 1 * ARCSEC
    assert abs(fitted.fx / camera.fx - 1.0) < 1e-3
    assert residual.shape == x.shape and np.all(residual < 0.5 * PIXEL)
    deleted = refine.leave_one_out_residuals(matrix, fitted, ref, x, y, fit_focal=case[2])
    assert deleted.shape == x.shape and not np.any(np.isnan(deleted))


def test_every_input_layout_runs_the_one_compiled_signature():
    """Read-only, Fortran-ordered, float32 and integer inputs are converted, not compiled again."""
    refine.warm_up_pose()
    kernels = (refine._kernel().fit, refine._kernel().fill_system, refine._kernel().deleted_residuals)
    compiled = [len(f.signatures) for f in kernels]
    camera = Camera(width=1024, height=1024, fx=5000, cx=512, cy=511)  # integers
    rot, ref, x, y = _field(camera, 12, seed=12)
    ref.setflags(write=False)
    matrix = np.asfortranarray(rot.as_matrix())
    matrix, fitted, _ = refine.fit_pose(matrix, camera, ref, x.astype(np.float32), np.round(y).astype(int),
                                        fit_focal=True)
    refine.leave_one_out_residuals(np.asfortranarray(matrix), fitted, ref, x, y.astype(np.float32), fit_focal=True)
    assert [len(f.signatures) for f in kernels] == compiled == [1, 1, 1]


def test_importing_startrack_does_not_import_numba():
    code = "import sys, startrack, startrack.identify._refine; print('numba' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout == "False\n"
