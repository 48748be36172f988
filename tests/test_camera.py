"""startrack.camera: projection, Brown-Conrady distortion, field of view, presets, validation."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest

from startrack.camera import (
    PRESETS,
    Camera,
    focal_px_from_fov,
    fov_from_focal_px,
    get_preset,
)
from startrack.errors import InvalidInputError
from startrack.frames import angle_between
from startrack.units import DEG, PIXEL

RNG_SEED = 2718
ROUND_TRIP_TOL = 1e-6 * PIXEL


def _frame_points(cam: Camera, n_random: int = 2000, seed: int = RNG_SEED):
    """Pixel positions covering the frame: the four outer corners, the edges and random points."""
    lo_x, hi_x, lo_y, hi_y = -0.5, cam.width - 0.5, -0.5, cam.height - 0.5
    gx, gy = np.meshgrid(np.linspace(lo_x, hi_x, 41), np.linspace(lo_y, hi_y, 31))
    rng = np.random.default_rng(seed)
    x = np.concatenate([gx.ravel(), rng.uniform(lo_x, hi_x, n_random)])
    y = np.concatenate([gy.ravel(), rng.uniform(lo_y, hi_y, n_random)])
    return x, y


def _opencv_project(v, fx, fy, cx, cy, k1, k2, p1, p2, k3):
    """OpenCV's projectPoints model (distortion vector (k1, k2, p1, p2, k3)), written out here.

    OpenCV also puts integer pixel coordinates at pixel centres, 0-based, like startrack.
    """
    xp = v[:, 0] / v[:, 2]
    yp = v[:, 1] / v[:, 2]
    r2 = xp**2 + yp**2
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    xpp = xp * radial + 2 * p1 * xp * yp + p2 * (r2 + 2 * xp**2)
    ypp = yp * radial + p1 * (r2 + 2 * yp**2) + 2 * p2 * xp * yp
    return fx * xpp + cx, fy * ypp + cy


# --- round trips -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(PRESETS))
def test_pixel_vector_pixel_round_trip_over_whole_frame(name):
    cam = get_preset(name)
    x, y = _frame_points(cam)
    v = cam.pixel_to_vector(x, y)
    np.testing.assert_allclose(np.linalg.norm(v, axis=-1), 1.0, atol=1e-15)
    assert np.all(v[:, 2] > 0)
    x2, y2 = cam.vector_to_pixel(v)
    assert np.max(np.hypot(x2 - x, y2 - y)) < ROUND_TRIP_TOL


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_vector_pixel_vector_round_trip(name):
    cam = get_preset(name)
    rng = np.random.default_rng(RNG_SEED + 1)
    half_w = 0.45 * cam.width / cam.fx
    half_h = 0.45 * cam.height / cam.fy
    v = np.column_stack([rng.uniform(-half_w, half_w, 500), rng.uniform(-half_h, half_h, 500),
                         np.ones(500)])
    x, y = cam.vector_to_pixel(v)
    back = cam.pixel_to_vector(x, y)
    # 1e-6 px expressed as an angle at this camera's scale
    assert np.max(angle_between(back, v)) < ROUND_TRIP_TOL / min(cam.fx, cam.fy)


def test_distorted_presets_are_distorted():
    for name in ("aptina-mt9p031", "droid-x2"):
        cam = get_preset(name)
        assert cam.has_distortion
        pinhole = dataclasses.replace(cam, k1=0.0, k2=0.0, k3=0.0, p1=0.0, p2=0.0)
        v = cam.pixel_to_vector(-0.5, -0.5)
        x, y = pinhole.vector_to_pixel(v)
        assert math.hypot(x + 0.5, y + 0.5) > 10 * PIXEL  # distortion moves the corner a lot


# --- against OpenCV's formula ----------------------------------------------------------------
@pytest.mark.parametrize("case", range(6))
def test_vector_to_pixel_matches_opencv_model(case):
    rng = np.random.default_rng(RNG_SEED + 10 + case)
    params = {"fx": rng.uniform(500, 4000), "fy": rng.uniform(500, 4000),
              "cx": rng.uniform(300, 700), "cy": rng.uniform(200, 500),
              "k1": rng.uniform(-0.3, 0.3), "k2": rng.uniform(-0.3, 0.3),
              "p1": rng.uniform(-1e-3, 1e-3), "p2": rng.uniform(-1e-3, 1e-3),
              "k3": rng.uniform(-0.1, 0.1)}
    if case == 0:
        params.update(k1=-0.1755, k2=0.1983, p1=0.0002264, p2=0.0, k3=0.0)  # aptina values
    cam = Camera(width=1000, height=700, **params)
    v = np.column_stack([rng.uniform(-0.3, 0.3, 300), rng.uniform(-0.3, 0.3, 300),
                         rng.uniform(0.5, 2.0, 300)])  # not unit length, on purpose
    x, y = cam.vector_to_pixel(v)
    ref_x, ref_y = _opencv_project(v, **params)
    np.testing.assert_allclose(x, ref_x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(y, ref_y, rtol=0, atol=1e-9)


def test_pinhole_projection_and_principal_point():
    cam = Camera(width=101, height=51, fx=200.0, fy=100.0)
    assert (cam.cx, cam.cy) == (50.0, 25.0)  # centre of the middle pixel, 0-based
    x, y = cam.vector_to_pixel([[0.0, 0.0, 1.0], [0.1, -0.2, 2.0]])
    np.testing.assert_allclose(x, [50.0, 50.0 + 200.0 * 0.05])
    np.testing.assert_allclose(y, [25.0, 25.0 - 100.0 * 0.1])


# --- field of view ---------------------------------------------------------------------------
@pytest.mark.parametrize(("width", "height", "fov"), [(1280, 1024, 30.06), (512, 512, 8.0),
                                                      (3264, 2448, 120.0), (640, 480, 0.5)])
def test_from_fov_and_fov_deg_agree(width, height, fov):
    cam = Camera.from_fov(width, height, fov)
    assert cam.fov_deg == pytest.approx(fov, abs=1e-10)
    expected_h = 2 * math.degrees(math.atan(math.tan(math.radians(fov) / 2) * height / width))
    assert cam.fov_height_deg == pytest.approx(expected_h, abs=1e-10)
    # geometry: the angle between the outer edges of the outer pixels is the FOV
    edges = cam.pixel_to_vector([-0.5, width - 0.5], [cam.cy, cam.cy])
    assert angle_between(edges[0], edges[1]) == pytest.approx(fov * DEG, abs=1e-12)
    corners = cam.pixel_to_vector([-0.5, width - 0.5], [-0.5, height - 0.5])
    assert angle_between(corners[0], corners[1]) == pytest.approx(cam.fov_diagonal_deg * DEG,
                                                                   abs=1e-12)


def test_focal_and_fov_helpers_are_inverse():
    for fov in (0.01, 0.3, 1.0, 3.0):
        assert fov_from_focal_px(800, focal_px_from_fov(800, fov)) == pytest.approx(fov, rel=1e-14)


def test_pixel_scale():
    cam = Camera.from_fov(1000, 1000, 10.0)
    centre = cam.pixel_to_vector([cam.cx, cam.cx + 1.0], [cam.cy, cam.cy])
    scale_arcsec = angle_between(centre[0], centre[1]) / DEG * 3600.0
    assert cam.pixel_scale_arcsec == pytest.approx(scale_arcsec, rel=1e-6)


@pytest.mark.parametrize(("name", "fov_w", "fov_h"), [("far-mst", 30.06, 24.25),
                                                      ("starnav-i", 8.0, 8.0)])
def test_preset_fov_matches_seed_values(name, fov_w, fov_h):
    cam = get_preset(name)
    assert cam.fov_deg == pytest.approx(fov_w, abs=0.02)
    assert cam.fov_height_deg == pytest.approx(fov_h, abs=0.02)


def test_with_focal_keeps_ratio():
    cam = get_preset("sunsat")
    scaled = cam.with_focal(2 * cam.fx)
    assert scaled.fy == pytest.approx(2 * cam.fy)
    assert (scaled.width, scaled.k1) == (cam.width, cam.k1)


# --- bad input and edge cases ----------------------------------------------------------------
@pytest.mark.parametrize("kwargs", [
    {"fx": -100.0}, {"fx": 0.0}, {"fx": float("nan")}, {"fx": float("inf")},
    {"fx": 100.0, "fy": -1.0}, {"width": 0}, {"height": 1}, {"width": 100.5},
    {"cx": float("nan")}, {"k1": float("inf")},
])
def test_bad_camera_parameters(kwargs):
    args = {"width": 100, "height": 80, "fx": 100.0} | kwargs
    with pytest.raises(InvalidInputError, match="camera"):
        Camera(**args)


@pytest.mark.parametrize("fov", [0.0, -5.0, 180.0, 200.0, float("nan")])
def test_bad_fov(fov):
    with pytest.raises(InvalidInputError, match="fov"):
        Camera.from_fov(640, 480, fov)
    with pytest.raises(InvalidInputError, match="field of view"):
        focal_px_from_fov(640, math.radians(fov))


def test_bad_focal_for_fov():
    with pytest.raises(InvalidInputError, match="focal length"):
        fov_from_focal_px(640, -3.0)


def test_directions_behind_or_beside_the_camera_are_nan():
    cam = get_preset("droid-x2")
    x, y = cam.vector_to_pixel([[0.1, 0.1, -1.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0],
                                [0.0, 0.0, 1.0]])
    assert np.all(np.isnan(x[:3])) and np.all(np.isnan(y[:3]))
    assert np.isfinite(x[3]) and np.isfinite(y[3])


def test_bad_shapes_and_values():
    cam = get_preset("far-mst")
    with pytest.raises(InvalidInputError, match=r"\(\.\.\., 3\)"):
        cam.vector_to_pixel([[1.0, 2.0]])
    with pytest.raises(InvalidInputError, match="finite"):
        cam.pixel_to_vector([1.0, np.nan], [2.0, 3.0])


def test_in_image_edges():
    cam = Camera.from_fov(10, 8, 5.0)
    x = np.array([-0.5, -0.51, 9.5, 9.51, 4.0, np.nan])
    y = np.array([-0.5, 0.0, 7.5, 0.0, 7.51, 1.0])
    np.testing.assert_array_equal(cam.in_image(x, y), [True, False, True, False, False, False])
    assert not cam.in_image(0.0, 0.0, margin_px=1.0)
    assert cam.in_image(0.5, 0.5, margin_px=1.0)


def test_get_preset_names():
    assert get_preset(" FAR_MST ") is PRESETS["far-mst"]
    with pytest.raises(InvalidInputError) as info:
        get_preset("hubble")
    message = str(info.value)
    assert "hubble" in message
    for name in PRESETS:
        assert name in message


def test_presets_record_their_source():
    """Each preset names the document it comes from by its key in docs/references.md, then where."""
    references = (Path(__file__).resolve().parents[1] / "docs" / "references.md").read_text(encoding="utf-8")
    for name, cam in PRESETS.items():
        assert cam.name == name
        key = re.match(r"[A-Z][a-z]+ (19|20)\d\d", cam.source)
        assert key and f"**{key.group(0)}**" in references, cam.source
        assert len(cam.source) > len(key.group(0)) + 5, "and where in it (a table or section)"


@pytest.mark.parametrize("fov", [np.float32(10.0), np.int64(10)])
def test_from_fov_accepts_numpy_scalars(fov):
    assert Camera.from_fov(640, 480, fov).fov_deg == pytest.approx(10.0, abs=1e-6)


def test_undistort_never_returns_a_silently_wrong_vector():
    cam = get_preset("droid-x2")
    x = np.array([2.0 * cam.width, 3.0 * cam.width, -1.5 * cam.width, cam.cx])
    y = np.array([2.0 * cam.height, cam.cy, cam.cy, cam.cy])
    try:
        v = cam.pixel_to_vector(x, y)
    except InvalidInputError:
        return  # refusing is an acceptable answer
    x2, y2 = cam.vector_to_pixel(v)
    error = np.hypot(x2 - x, y2 - y)
    assert np.all(np.isnan(error) | (error < ROUND_TRIP_TOL))


def test_pixel_aspect_is_fx_over_fy_everywhere():
    """A sensor whose rows are 1.9 pixel widths apart: fy = fx / 1.9, and a star 100 rows off
    the centre is 1.9 times as far off axis as one 100 columns off."""
    cam = Camera.from_fov(1024, 1024, 20.0, pixel_aspect=1.9)
    assert cam.pixel_aspect == pytest.approx(1.9)
    assert cam.fov_deg == pytest.approx(20.0)
    v = cam.pixel_to_vector([cam.cx + 100.0, cam.cx], [cam.cy, cam.cy + 100.0])
    assert v[1, 1] / v[1, 2] == pytest.approx(1.9 * v[0, 0] / v[0, 2], rel=1e-12)
    assert cam.with_pixel_aspect(1.0).fy == cam.fx
    assert cam.with_focal(2 * cam.fx).pixel_aspect == pytest.approx(1.9)  # fx and fy scale together


@pytest.mark.parametrize(("kwargs", "word"), [({"pixel_pitch_um": -2.0}, "pixel_pitch_um"),
                                              ({"pixel_pitch_um": float("nan")}, "pixel_pitch_um"),
                                              ({"fy": -5.0}, "fy")])
def test_nonsense_camera_values_are_refused(kwargs, word):
    with pytest.raises(InvalidInputError, match=word):
        Camera(width=100, height=100, fx=500.0, **kwargs)
    with pytest.raises(InvalidInputError, match="pixel_aspect"):
        Camera.from_fov(100, 100, 10.0, pixel_aspect=0.0)


@pytest.mark.parametrize(("key", "value"), [
    ("fx", None), ("fx", "500"), ("fx", np.array([500.0, 510.0])), ("fy", "abc"), ("fy", True),
    ("cx", "49.5"), ("cy", [49.5]), ("k1", None), ("k2", np.zeros(3)), ("k3", "0"), ("p1", b"0"),
    ("p2", {"p2": 0.0}),
])
def test_a_field_that_is_not_a_number_is_refused_by_name(key, value):
    args = {"width": 100, "height": 100, "fx": 500.0} | {key: value}
    with pytest.raises(InvalidInputError, match=rf"camera {key} must be a real number \(") as info:
        Camera(**args)
    assert type(value).__name__ in str(info.value)


@pytest.mark.parametrize(("key", "value"), [("name", None), ("name", []), ("source", {"a": 1}), ("source", 3)])
def test_a_label_that_is_not_a_string_is_refused_by_name(key, value):
    # a rig or camera JSON file with "name": [] made a Camera whose name was a list
    with pytest.raises(InvalidInputError, match=re.escape(f"camera {key} must be a string, got {value!r}")):
        Camera(width=100, height=100, fx=500.0, **{key: value})


def test_numpy_and_integer_fields_are_stored_as_floats():
    cam = Camera(width=100, height=100, fx=np.float32(500.0), fy=510, cx=np.int64(50), k1=np.float64(-0.1))
    assert all(type(getattr(cam, key)) is float for key in ("fx", "fy", "cx", "cy", "k1", "k2"))
    assert (cam.fx, cam.fy, cam.cx, cam.k1) == (500.0, 510.0, 50.0, -0.1)


def test_with_focal_and_with_distortion_name_a_value_that_is_not_a_number():
    cam = Camera(width=100, height=100, fx=500.0)
    with pytest.raises(InvalidInputError, match=r"camera fx must be a real number"):
        cam.with_focal("600")
    with pytest.raises(InvalidInputError, match=r"camera fy must be a real number"):
        cam.with_focal(600.0, [600.0])
    with pytest.raises(InvalidInputError, match=r"camera k2 must be a real number"):
        cam.with_distortion(k1=-0.1, k2="0.01")
    assert cam.with_distortion(k1=np.float32(-0.25)).k1 == -0.25


@pytest.mark.parametrize("name", [np.zeros(3), ["far-mst"], 3, None])
def test_a_preset_name_that_is_not_a_string_is_refused(name):
    # before: AttributeError ("object has no attribute 'strip'")
    from startrack.simulate import get_sensor_preset

    for lookup in (get_preset, get_sensor_preset):
        with pytest.raises(InvalidInputError, match=re.escape(f"a preset name must be a string, got {name!r}")):
            lookup(name)
