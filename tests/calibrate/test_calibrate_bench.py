"""Checkerboard calibration with OpenCV (Fowler 2013 Ch. 4): corners from rendered images, the
3-sigma pruning rule, rejection of a bad view, and the residual report."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

pytest.importorskip("cv2", reason="bench calibration needs opencv-python-headless")

from startrack.calibrate._bench import (  # noqa: E402
    Checkerboard,
    calibrate_checkerboard,
    find_corners,
    render_checkerboard,
)
from startrack.calibrate._lens_models import distortion_field_px  # noqa: E402
from startrack.camera import Camera, get_preset  # noqa: E402
from startrack.errors import InvalidInputError  # noqa: E402
from startrack.units import PIXEL  # noqa: E402

BOARD = Checkerboard(columns=9, rows=6, square_mm=25.0)


def _poses(n, rng, distance_mm, spread_mm):
    gen = np.random.default_rng(rng)
    centre = np.array([(BOARD.columns - 1) / 2, (BOARD.rows - 1) / 2, 0.0]) * BOARD.square_mm
    for _ in range(n):
        rot = Rotation.from_euler("xyz", [gen.uniform(-35, 35), gen.uniform(-35, 35), gen.uniform(-20, 20)],
                                  degrees=True)
        where = np.array([gen.uniform(-spread_mm, spread_mm), gen.uniform(-0.7 * spread_mm, 0.7 * spread_mm),
                          distance_mm])
        yield rot, where - rot.apply(centre)


def _projected_corners(camera, n, rng, sigma_px=0.05):
    gen = np.random.default_rng(rng + 100)
    out = []
    for rot, origin in _poses(n, rng, 420.0, 160.0):
        pts = rot.apply(BOARD.object_points().astype(float)) + origin
        x, y = camera.vector_to_pixel(pts)
        out.append(np.stack([x, y], axis=1) + gen.normal(0, sigma_px, (x.size, 2)))
    return out


def _distortion_rms(a, b):
    return float(np.sqrt(np.mean(np.sum((distortion_field_px(a)[2] - distortion_field_px(b)[2]) ** 2, axis=1))))


def test_aptina_from_corners_with_a_bad_view_and_pruning():
    truth = get_preset("aptina-mt9p031")
    corners = _projected_corners(truth, 16, rng=1)
    corners[5] = corners[5] + np.random.default_rng(9).normal(0, 2.0, corners[5].shape)  # a blurred view
    corners.append(None)  # a view where the board was not found
    result = calibrate_checkerboard(corners, BOARD, truth.width, truth.height)
    assert 5 in result.rejected_views and 16 not in result.used_views
    cam = result.camera
    assert abs(cam.fx / truth.fx - 1) < 5e-4 and abs(cam.fy / truth.fy - 1) < 5e-4
    assert np.hypot(cam.cx - truth.cx, cam.cy - truth.cy) < 1.0 * PIXEL
    assert _distortion_rms(cam, truth) < 0.1 * PIXEL
    assert "k3" in result.pruned and cam.k3 == 0.0
    assert result.rms_px == pytest.approx(0.05 * np.sqrt(2), rel=0.25)
    assert all(s > 0 for s in result.sigma.values()) and "k3" not in result.sigma


def test_rendered_checkerboard_images_calibrate_a_small_camera():
    truth = Camera(width=480, height=360, fx=520.0, fy=521.0, cx=243.0, cy=176.0, k1=-0.17, k2=0.2)
    poses = _poses(12, 3, 480.0, 90.0)
    images = [render_checkerboard(truth, BOARD, rot, origin, supersample=2) for rot, origin in poses]
    corners = [find_corners(img, BOARD) for img in images]
    assert sum(c is not None for c in corners) >= 8
    result = calibrate_checkerboard(corners, BOARD, truth.width, truth.height)
    assert abs(result.camera.fx / truth.fx - 1) < 5e-3
    assert _distortion_rms(result.camera, truth) < 0.3 * PIXEL
    assert result.rms_px < 0.3 * PIXEL


def test_blank_image_and_too_few_views():
    assert find_corners(np.zeros((100, 120)), BOARD) is None
    with pytest.raises(InvalidInputError, match="at least 3"):
        calibrate_checkerboard([None, None], BOARD, 100, 100)
    with pytest.raises(InvalidInputError, match="inner corners"):
        Checkerboard(2, 5, 10.0)
