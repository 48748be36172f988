"""Calibration from identified stars on simulated frames of the Fowler 2013 cameras (their published
focal lengths, principal points and Brown-Conrady distortion), from 1 frame and from 20."""

import numpy as np
import pytest

from startrack.calibrate._lens_models import distortion_field_px
from startrack.calibrate._stars import CalibrationFrame, calibrate_from_stars
from startrack.camera import Camera, get_preset
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error
from startrack.results import Status
from startrack.units import PIXEL

from .sim_frames import make_frames

ALL = ("f", "aspect", "cx", "cy", "k1", "k2", "k3", "p1", "p2")


def _uncalibrated(camera: Camera) -> Camera:
    """What a user starts from: the nominal focal length (1 % off), centred, no distortion."""
    return Camera(width=camera.width, height=camera.height, fx=camera.fx * 1.01)


def _distortion_rms_px(a: Camera, b: Camera) -> float:
    _, _, da = distortion_field_px(a)
    _, _, db = distortion_field_px(b)
    return float(np.sqrt(np.mean(np.sum((da - db) ** 2, axis=1))))


@pytest.mark.parametrize("preset", ["aptina-mt9p031", "droid-x2"])
@pytest.mark.parametrize("n_frames", [1, 20])
def test_calibration_recovers_the_seed_cameras(preset, n_frames):
    """Focal length to 0.05 %, principal point to 0.5 px, distortion to 0.1 px RMS over the frame."""
    truth = get_preset(preset)
    frames, rots = make_frames(truth, n_frames, rng=11, max_mag=6.0 if n_frames == 1 else 5.0)
    result = calibrate_from_stars(frames, _uncalibrated(truth), fit=ALL)
    assert result.status is Status.OK
    cam = result.camera
    assert abs(cam.fx / truth.fx - 1) < 0.0005
    assert abs(cam.fy / truth.fy - 1) < 0.0005
    assert np.hypot(cam.cx - truth.cx, cam.cy - truth.cy) < 0.5 * PIXEL
    assert _distortion_rms_px(cam, truth) < 0.1 * PIXEL
    assert max(attitude_error(t, r) for t, r in zip(rots, result.rotations, strict=True)) < 0.5 / truth.fx
    assert result.rms_px == pytest.approx(0.1 * np.sqrt(2), rel=0.2)  # the injected centroid noise
    assert {"k3", "p2"} <= set(result.pruned)  # zero in both published calibrations


def test_uncertainties_describe_the_errors():
    truth = get_preset("droid-x2")
    frames, _ = make_frames(truth, 3, rng=5)
    result = calibrate_from_stars(frames, _uncalibrated(truth), fit=ALL)
    errors = {"f": result.params["f"] - truth.fx, "cx": result.camera.cx - truth.cx,
              "cy": result.camera.cy - truth.cy, "k1": result.params["k1"] - truth.k1,
              "k2": result.params["k2"] - truth.k2}
    z = np.array([errors[k] / result.sigma[k] for k in errors])
    assert np.all(np.abs(z) < 4.0), z
    assert 0 < result.sigma["f"] < 1.0


def test_outliers_are_rejected():
    truth = get_preset("aptina-mt9p031")
    frames, _ = make_frames(truth, 2, rng=3, outliers=5)
    result = calibrate_from_stars(frames, _uncalibrated(truth), fit=ALL)
    assert result.n_outliers >= 10
    assert result.rms_px < 0.2 * PIXEL
    assert _distortion_rms_px(result.camera, truth) < 0.1 * PIXEL


def test_pruning_fixes_insignificant_coefficients_to_zero():
    truth = get_preset("aptina-mt9p031").with_distortion(p1=0.0)
    frames, _ = make_frames(truth, 1, rng=2)
    result = calibrate_from_stars(frames, _uncalibrated(truth), fit=ALL)
    for name in result.pruned:
        assert result.params[name] == 0.0 and name not in result.sigma
    assert "p1" in result.pruned and "k1" not in result.pruned
    unpruned = calibrate_from_stars(frames, _uncalibrated(truth), fit=ALL, prune=False)
    assert unpruned.pruned == () and set(unpruned.fitted) == set(ALL)


def test_too_few_stars_is_a_status_and_bad_names_raise():
    camera = Camera.from_fov(640, 480, 20.0)
    frame = CalibrationFrame(np.array([1.0, 2.0]), np.array([3.0, 4.0]), np.eye(3)[:2], get_rot())
    assert calibrate_from_stars([frame], camera).status is Status.TOO_FEW_STARS
    with pytest.raises(InvalidInputError, match="fit"):
        calibrate_from_stars([frame], camera, fit=("focal",))
    with pytest.raises(InvalidInputError, match="vectors_icrs"):
        CalibrationFrame(np.zeros(3), np.zeros(3), np.zeros((2, 3)), get_rot())


def get_rot():
    from scipy.spatial.transform import Rotation

    return Rotation.identity()
