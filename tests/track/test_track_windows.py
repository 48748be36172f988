"""The tracking step's parts: quaternion arithmetic, one-to-one matching, the cached catalog cone
of the window matcher, and the confirmation that refuses a wrong prediction."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.attitude._propagation import propagate
from startrack.attitude._qmethod import q_method_quaternions
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, attitude_error, boresight, random_rotations
from startrack.identify._field_stars import field_stars
from startrack.identify._verify import match_nearest
from startrack.rate import rate_between
from startrack.track import Tracker, match_in_windows
from startrack.track import _windows as windows
from startrack.track._quaternions import fit_quat, quat_conjugate, quat_matrix, quat_product, quat_rotvec, rotvec_quat
from startrack.track._windows import WindowMatcher, one_to_one, project
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(1024, 1024, 15.0)
PIXEL = CAMERA.pixel_scale_arcsec * ARCSEC
STARS = field_stars(9.5, 2000.0)


def _quat(rot: Rotation) -> tuple:
    return tuple(rot.as_quat().tolist())


def test_quaternion_helpers_agree_with_scipy():
    rots = random_rotations(20, rng=5)
    for p, q in zip(rots[:10], rots[10:], strict=True):
        assert attitude_error(Rotation.from_quat(quat_product(_quat(p), _quat(q))), p * q) < 1e-14
        np.testing.assert_allclose(quat_matrix(_quat(p)), p.as_matrix(), atol=1e-15)
        np.testing.assert_allclose(quat_rotvec(quat_product(_quat(q), quat_conjugate(_quat(p)))),
                                   (q * p.inv()).as_rotvec(), atol=1e-14)
    for rotvec in ([0.0, 0.0, 0.0], [1e-12, -2e-12, 0.0], [0.3, -1.2, 0.7], [0.0, math.pi - 1e-9, 0.0]):
        assert attitude_error(Rotation.from_quat(rotvec_quat(np.array(rotvec))), Rotation.from_rotvec(rotvec)) < 1e-15
        np.testing.assert_allclose(quat_rotvec(rotvec_quat(np.array(rotvec))), rotvec, atol=1e-15)


def test_prediction_and_rate_match_propagate_and_rate_between():
    rot = random_rotations(None, rng=2)
    rate = np.array([0.4, -1.1, 2.3]) * DEG
    turned = Rotation.from_quat(quat_product(rotvec_quat(-rate * 0.1), _quat(rot)))
    assert attitude_error(turned, propagate(rot, rate, 0.1)) < 1e-14
    later = propagate(rot, rate, 0.1)
    measured = -quat_rotvec(quat_product(_quat(later), quat_conjugate(_quat(rot)))) / 0.1
    np.testing.assert_allclose(measured, rate_between(rot, later, 0.1), atol=1e-12)


def test_fit_quat_is_the_q_method():
    rng = np.random.default_rng(4)
    truth = random_rotations(None, rng)
    reference = rng.normal(size=(12, 3))
    reference /= np.linalg.norm(reference, axis=1, keepdims=True)
    observed = truth.apply(reference) + rng.normal(0, 10 * ARCSEC, (12, 3))
    observed /= np.linalg.norm(observed, axis=1, keepdims=True)
    expected = q_method_quaternions(observed[None], reference[None], np.full((1, 12), 1 / 12))[0]
    assert attitude_error(Rotation.from_quat(fit_quat(observed, reference)), Rotation.from_quat(expected)) < 1e-12
    assert attitude_error(Rotation.from_quat(fit_quat(observed, reference)), truth) < 20 * ARCSEC


@pytest.mark.parametrize("seed", range(6))
def test_one_to_one_gives_the_pairs_of_match_nearest(seed):
    # crowded: many detections have two or more candidates in the radius, so the order matters
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, 100, 40), rng.uniform(0, 100, 40)
    px, py = np.r_[x[:30] + rng.normal(0, 2, 30), rng.uniform(0, 100, 50)], np.r_[y[:30] + rng.normal(0, 2, 30),
                                                                                   rng.uniform(0, 100, 50)]
    for radius in (1.0, 4.0, 15.0):
        got, expected = one_to_one(x, y, px, py, radius), match_nearest(x, y, px, py, radius)
        np.testing.assert_array_equal(got[0], expected[0])
        np.testing.assert_array_equal(got[1], expected[1])
    assert all(part.size == 0 for part in one_to_one(x[:0], y[:0], px, py, 5.0))
    assert all(part.size == 0 for part in one_to_one(x, y, px[:0], py[:0], 5.0))


def test_project_is_vector_to_pixel():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(3, 50)) * [[0.1], [0.1], [1.0]]
    v[2] = np.abs(v[2]) + 0.1
    distorted = CAMERA.with_distortion(k1=-0.1, p1=1e-3)
    for camera in (CAMERA, distorted):
        np.testing.assert_allclose(project(camera, v), camera.vector_to_pixel(v.T), rtol=1e-14)
    v[2, 7] = -0.5  # behind the camera: NaN, never a mirrored position
    x, y = project(CAMERA, v)
    assert np.isnan(x[7]) and np.isnan(y[7]) and np.all(np.isfinite(np.delete(x, 7)))


def _brute_force_predicted(matrix, margin_rad, count):
    half_diag = math.radians(CAMERA.fov_diagonal_deg) / 2 + margin_rad
    near = np.flatnonzero(STARS.vectors @ matrix[2] >= math.cos(min(half_diag, 1.5)))
    x, y = CAMERA.vector_to_pixel(STARS.vectors[near] @ matrix.T)
    return near[CAMERA.in_image(x, y)][:count]


@pytest.mark.parametrize("prefix_factor", [2.0, 0.3])
def test_the_cached_cone_predicts_the_stars_a_full_search_finds(prefix_factor, monkeypatch):
    # a slow drift (the cone is reused), a jump past its slack (queried again), a big margin;
    # a small prefix factor makes the brightest prefix too short, so that all stars are projected
    monkeypatch.setattr(windows, "PREFIX_FACTOR", prefix_factor)
    matcher = WindowMatcher(CAMERA, STARS)
    start = random_rotations(None, rng=8)
    turns = [Rotation.from_rotvec([0.3 * k * DEG, -0.2 * k * DEG, 0.5 * k * DEG]) for k in range(12)]
    turns += [Rotation.from_rotvec([0.0, 5 * DEG, 0.0]), Rotation.from_rotvec([40 * DEG, 0.0, 0.0])]
    for turn, margin, count in zip(turns, [0.0] * 12 + [1 * DEG, 0.0], [80] * 11 + [400, 80, 30], strict=True):
        matrix = (turn * start).as_matrix()
        idx, x, y = matcher.predicted(matrix, margin, count)
        np.testing.assert_array_equal(idx, _brute_force_predicted(matrix, margin, count))
        np.testing.assert_allclose(np.c_[x, y], np.c_[CAMERA.vector_to_pixel(STARS.vectors[idx] @ matrix.T)],
                                   atol=1e-9)


def _detections(truth, rng, n=40):
    idx = _brute_force_predicted(truth.as_matrix(), 0.0, n)
    x, y = CAMERA.vector_to_pixel(truth.apply(STARS.vectors[idx]))
    return x + rng.normal(0, 0.2, x.size), y + rng.normal(0, 0.2, y.size)


def test_window_matcher_refits_a_prediction_and_refuses_a_wrong_one():
    rng = np.random.default_rng(6)
    truth = random_rotations(None, rng)
    x, y = _detections(truth, rng)
    matcher = WindowMatcher(CAMERA, STARS)
    near = Rotation.from_rotvec([0.0, 0.0, 20 * ARCSEC]) * Rotation.from_rotvec([15 * ARCSEC, 0.0, 0.0]) * truth
    found = matcher.match(x, y, near.as_matrix(), window_px=8.0, match_px=2.0, min_stars=5)
    assert found.image_index.size == 40 and found.residual_rms_px < 0.4
    # 40 stars with 0.2 px noise: the boresight to a few hundredths of a pixel, roll ~10x worse
    assert angle_between(boresight(truth), boresight(found.rot_cam_from_icrs)) < 0.1 * PIXEL
    assert attitude_error(truth, found.rot_cam_from_icrs) < 1 * PIXEL
    again = match_in_windows(x, y, CAMERA, near, STARS, window_px=8.0, match_px=2.0, min_stars=5)
    assert attitude_error(again.rot_cam_from_icrs, found.rot_cam_from_icrs) < 1e-12
    # 1 deg off in roll: the stars within ~450 px of the centre are in their windows, and the
    # refit brings in the rest
    rolled = Rotation.from_rotvec([0.0, 0.0, 1 * DEG]) * truth
    recovered = matcher.match(x, y, rolled.as_matrix(), window_px=8.0, match_px=2.0, min_stars=5)
    assert recovered.image_index.size == 40 and attitude_error(truth, recovered.rot_cam_from_icrs) < 1 * PIXEL
    # pointing 0.5-2 deg off: whatever falls into the windows is not confirmed
    for angle_deg in (0.5, 1.0, 2.0):
        wrong = Rotation.from_rotvec([angle_deg * DEG, 0.0, 0.0]) * truth
        refused = matcher.match(x, y, wrong.as_matrix(), window_px=8.0, match_px=2.0, min_stars=5)
        assert refused.rot_cam_from_icrs is None or refused.residual_rms_px > 1.0


def test_tracker_checks_the_gyro_rate():
    tracker = Tracker(camera=CAMERA)
    for bad in ([0.1, 0.2], [np.nan, 0.0, 0.0]):
        with pytest.raises(InvalidInputError, match="gyro_rate_rad_s"):
            tracker.update(np.zeros(0), np.zeros(0), 0.0, gyro_rate_rad_s=bad)
