"""The pose fit of the final stage: Gauss-Newton on rotation matrices, its Jacobian, and the re-match.

The fit and the re-match of :mod:`startrack.identify.final_fit` are written for speed (a few
fused numpy operations per step, a cell filter in front of the nearest-star match); these tests
pin them to what they replace: finite differences, scipy's rotations and a match over every
predicted star.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.frames import attitude_error
from startrack.identify import final_fit, refine
from startrack.identify.verify import match_nearest
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
    system = refine._system(camera, focal, matrix @ ref.T, offset, 5)
    assert np.allclose(system[-1], np.concatenate([x, y]) - np.concatenate(_pixels(matrix, camera, ref)),
                       atol=1e-9 * PIXEL)

    def predicted(params):
        turned = Rotation.from_rotvec(params[:3]).as_matrix() @ matrix
        moved = camera.with_focal(camera.fx * np.exp(params[3]), camera.fy * np.exp(params[3]))
        moved = moved.with_distortion(k1=camera.k1 + params[4])
        return np.concatenate(_pixels(turned, moved, ref))

    step = 1e-7
    for k in range(5):
        delta = np.zeros(5)
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


def _across_cell_borders(rng, radius):
    """Image stars, each with one predicted star just inside the radius along +x, -x, +y or -y,
    placed so that a cell border falls between the two: (x, y, px, py), (N,) each."""
    cell = final_fit.CELL_PX
    k = np.arange(2, 29, 2)  # every other cell border of a 1000 x 700 image, so stars stay apart
    col, row = np.meshgrid(k * cell - 0.5, k[k * cell < 690] * cell - 0.5)
    col, row = col.ravel(), row.ravel()
    jitter = rng.uniform(0, 0.1, col.size)
    direction = np.arange(col.size) % 4
    along = np.where(direction % 2 == 0, 1.0, -1.0) * (0.999 * radius)  # +, -, +, -
    start = np.where(along > 0, -along + jitter, -along - jitter)  # the border lies between star and prediction
    on_x = direction < 2
    x, y = np.where(on_x, col + start, col + 5.0), np.where(on_x, row + 5.0, row + start)
    return x, y, np.where(on_x, x + along, x), np.where(on_x, y, y + along)


def test_rematch_through_the_cells_equals_a_match_over_every_predicted_star():
    """Predicted stars just inside the radius across a cell border from their image star, others
    at up to twice the radius, some outside the image: the cell filter must not change a pair."""
    camera = Camera.from_fov(1000, 700, 15.0)
    radius = final_fit.REMATCH_RADIUS_PX
    rng = np.random.default_rng(6)
    x, y, px, py = _across_cell_borders(rng, radius)
    ox, oy = rng.uniform(-0.5, 999.5, 60), rng.uniform(-0.5, 699.5, 60)
    ox[:4], oy[:4] = [-0.5, 999.5, 3.0, 500.0], [10.0, 699.5, -0.5, 699.5]  # on the image border
    turn, dist = rng.uniform(0, 2 * np.pi, 60), rng.uniform(0, 2 * radius, 60)
    x, y = np.concatenate([x, ox]), np.concatenate([y, oy])
    px, py = np.concatenate([px, ox + dist * np.cos(turn)]), np.concatenate([py, oy + dist * np.sin(turn)])
    vectors = camera.pixel_to_vector(px, py)  # attitude: identity
    px, py = camera.vector_to_pixel(vectors)  # the positions the re-match predicts
    reach = final_fit._Reach.around(x, y, camera.width, camera.height, radius)
    rows = np.arange(px.size) + 1000
    field = final_fit._Field(x, y, reach, rows, vectors, True)
    img, got_rows, ref = final_fit.rematch(field, np.eye(3), camera)
    inside = np.flatnonzero(camera.in_image(px, py))
    want_img, want_cat = match_nearest(x, y, px[inside], py[inside], radius)
    assert img.size > 100
    assert np.array_equal(img, want_img)
    assert np.array_equal(got_rows, rows[inside[want_cat]])
    assert np.array_equal(ref, vectors[inside[want_cat]])
