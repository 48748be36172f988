"""The self-calibration's joint test of the calibrated terms against the pinhole (F-test)."""

from startrack.calibrate._selfcal import justified
from startrack.calibrate._stars import CalibrationFrame, calibrate_from_stars
from startrack.camera import Camera, get_preset

from .sim_frames import make_frames

FEW_TERMS = ("f", "k1", "cx", "cy", "k2")


def _few_stars(frame: CalibrationFrame, n: int) -> CalibrationFrame:
    return CalibrationFrame(frame.x[:n], frame.y[:n], frame.vectors_icrs[:n], frame.rot_cam_from_icrs)


def test_terms_that_do_not_lower_the_residual_jointly_give_way_to_the_pinhole():
    """Twelve stars of a 6 deg pinhole with 0.3 px noise: five free terms fit the noise a little,
    not significantly; the result must be the pinhole (centred, square, undistorted)."""
    truth = Camera.from_fov(1280, 960, 6.0)
    frames, _ = make_frames(truth, 1, rng=4, sigma_px=0.3, max_mag=7.5)
    frame = _few_stars(frames[0], 12)
    cal = calibrate_from_stars(frame, truth, fit=FEW_TERMS, prune=False)
    assert set(cal.fitted) == set(FEW_TERMS)
    kept = justified(frame, cal)
    cam = kept.camera
    assert kept.fitted == ("f",) and not cam.has_distortion
    assert (cam.cx, cam.cy, cam.fy) == ((cam.width - 1) / 2, (cam.height - 1) / 2, cam.fx)


def test_a_real_distortion_keeps_its_terms():
    truth = get_preset("aptina-mt9p031")
    frames, _ = make_frames(truth, 1, rng=2, sigma_px=0.1)
    start = Camera(width=truth.width, height=truth.height, fx=truth.fx, fy=truth.fx)
    cal = calibrate_from_stars(frames[0], start, fit=FEW_TERMS)
    assert justified(frames[0], cal) is cal
    assert "k1" in cal.fitted
