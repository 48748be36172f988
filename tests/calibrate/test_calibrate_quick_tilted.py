"""Jacobs 1995's quick methods (single-pair focal length, optical centre by rotation) and its
tilted-CCD + radial model, fitted by the joint calibration."""

import math

import numpy as np
import pytest

from startrack.calibrate._quick import (
    centre_from_rotation,
    focal_from_pair,
    focal_from_stars,
    focal_sensitivity,
)
from startrack.calibrate._stars import calibrate_from_stars
from startrack.calibrate._tilted_ccd import TiltedCcdCamera, TiltedCcdModel
from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.units import DEG, PIXEL

from .sim_frames import make_frames


def test_single_pair_focal_length_is_exact_for_a_pinhole():
    f = 3846.15
    a = np.array([120.0, -40.0, f])
    b = np.array([-300.0, 250.0, f])
    theta = math.atan2(np.linalg.norm(np.cross(a, b)), a @ b)
    assert focal_from_pair(120.0, -40.0, -300.0, 250.0, theta) == pytest.approx(f, rel=1e-9)


def test_focal_from_identified_stars():
    camera = Camera(width=752, height=582, fx=3846.15)  # Jacobs 1995's 25 mm lens, square pixels
    frames, rots = make_frames(camera, 1, rng=4, sigma_px=0.1)
    fr = frames[0]
    vec_cam = rots[0].apply(fr.vectors_icrs)
    f, spread = focal_from_stars(fr.x, fr.y, vec_cam, camera.cx, camera.cy)
    assert f == pytest.approx(camera.fx, rel=2e-3)
    assert spread > 0
    with pytest.raises(InvalidInputError, match="two stars"):
        focal_from_stars([1.0], [2.0], [[0, 0, 1]], 0.0, 0.0)


def test_jacobs1995_sensitivity_25_um_of_focal_error_is_about_one_pixel_corner_to_corner():
    """Jacobs 1995 §6.1: stars at opposite corners (+-2.44, +-1.82) mm, f 25 mm: 25 um -> 0.23 mrad."""
    err = focal_sensitivity(2.44, 1.82, -2.44, -1.82, 25.0, 25.025)
    assert abs(err) == pytest.approx(0.23e-3, rel=0.1)


def test_optical_centre_from_rotation_tracks():
    rng = np.random.default_rng(1)
    cx, cy = 377.3, 290.8
    angles = np.radians(np.arange(0, 360, 10))  # 36 images at 10 deg steps, as in Jacobs 1995 App. F
    tracks = []
    for radius in (6.0, 150.0, 260.0):
        phase = rng.uniform(0, 2 * np.pi)
        tracks.append((cx + radius * np.cos(angles + phase) + rng.normal(0, 0.1, angles.size),
                       cy + radius * np.sin(angles + phase) + rng.normal(0, 0.1, angles.size)))
    fx, fy, radii = centre_from_rotation(tracks)
    assert np.hypot(fx - cx, fy - cy) < 0.05 * PIXEL
    np.testing.assert_allclose(radii, [6.0, 150.0, 260.0], atol=0.05)


def test_tilted_ccd_round_trip_and_seed_values():
    cam = TiltedCcdCamera.from_tilt(752, 582, 3846.0, 375.5, 290.5, 0.733 * DEG, 306 * DEG,
                                    c1=1e-3, c2=-8e-5 * 25, c3=-4.4e-4 * 625)
    assert math.degrees(cam.theta_max_rad) == pytest.approx(0.733)
    assert math.degrees(cam.phi_max_rad) == pytest.approx(306.0)
    x, y = np.meshgrid(np.linspace(0, 751, 9), np.linspace(0, 581, 7))
    v = cam.pixel_to_vector(x.ravel(), y.ravel())
    bx, by = cam.vector_to_pixel(v)
    np.testing.assert_allclose(bx, x.ravel(), atol=1e-6)
    np.testing.assert_allclose(by, y.ravel(), atol=1e-6)
    pinhole = Camera(width=752, height=582, fx=3846.0)
    px, py = pinhole.vector_to_pixel(v)
    assert 0.3 < np.max(np.hypot(px - x.ravel(), py - y.ravel())) < 5.0  # a pixel or so, as in the thesis


class _TiltedTruth:
    """Adapter so make_frames can project through the tilted model."""

    def __init__(self, cam: TiltedCcdCamera):
        self.cam = cam
        self.width, self.height, self.fx, self.fy = cam.width, cam.height, cam.f, cam.f
        self.cx, self.cy = cam.cx, cam.cy

    def vector_to_pixel(self, v):
        return self.cam.vector_to_pixel(v)

    def pixel_to_vector(self, x, y):
        return self.cam.pixel_to_vector(x, y)

    def in_image(self, x, y, margin_px=0.0):
        return Camera(width=self.width, height=self.height, fx=self.fx).in_image(x, y, margin_px)


def test_calibration_with_the_tilted_ccd_model():
    truth = TiltedCcdCamera.from_tilt(752, 582, 3846.0, 380.0, 286.0, 0.733 * DEG, 306 * DEG,
                                      c2=-2e-3, c3=-0.275)
    frames, _ = make_frames(_TiltedTruth(truth), 10, rng=6, sigma_px=0.1, max_mag=7.0)
    start = Camera(width=752, height=582, fx=3846.0 * 1.005)
    result = calibrate_from_stars(frames, start, fit=("f", "cx", "cy", "tilt_x", "tilt_y", "c2", "c3"),
                                  model=TiltedCcdModel(start), prune=False)
    fitted = TiltedCcdModel(start).tilted_camera(np.array(list(result.params.values())))
    x, y = np.meshgrid(np.linspace(0, 751, 15), np.linspace(0, 581, 12))
    fx, fy = fitted.vector_to_pixel(truth.pixel_to_vector(x.ravel(), y.ravel()))
    # the mapping, up to the rotation the attitudes absorb: compare after removing the mean shift
    dx, dy = fx - x.ravel(), fy - y.ravel()
    assert np.sqrt(np.mean((dx - dx.mean()) ** 2 + (dy - dy.mean()) ** 2)) < 0.1 * PIXEL
    assert result.rms_px < 0.2 * PIXEL
    assert result.camera is None and set(result.params) >= {"tilt_x", "tilt_y"}
