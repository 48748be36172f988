"""solve_image on a smeared catalog frame: solved from its streaks without being told, and it
says so (issue 19 item 1)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.frames import attitude_error
from startrack.io import Image
from startrack.rate import axis_error_rad
from startrack.rate._streak_solve import StreakSolution
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.solve import solve_image
from startrack.units import DEG

CAMERA = Camera.from_fov(1024, 1024, 12.0)
OMEGA = 2.0 * DEG * np.array([0.3, -0.9, 0.2]) / np.linalg.norm([0.3, -0.9, 0.2])
EXPOSURE_S = 0.2  # streaks of about 33 px: the point solve finds no match on this frame


@pytest.fixture(scope="module")
def smeared():
    sensor = get_sensor_preset("generic-cmos").with_exposure(EXPOSURE_S)
    return simulate_frame(CAMERA, Rotation.from_euler("zyx", [40, 20, 10], degrees=True), max_mag=7.5,
                          epoch_jyear=2025.0, sensor=sensor, rng=1, rate_rad_s=OMEGA)


def test_a_smeared_frame_is_solved_from_its_streaks_at_mid_exposure(smeared):
    image = Image(np.asarray(smeared.image), header={"EXPTIME": EXPOSURE_S})
    solution = solve_image(image, fov_deg=12.0, epoch=2025.0)
    assert isinstance(solution, StreakSolution) and solution.mode == "streak" and solution.solved
    assert attitude_error(smeared.truth.rot_cam_from_icrs, solution.rot_cam_from_icrs) < CAMERA.pixel_scale_arcsec \
        * np.pi / (180 * 3600)  # within a pixel (42 arcsec) of the mid-exposure attitude
    assert solution.t_mid_s == pytest.approx(EXPOSURE_S / 2)  # the header's exposure, global shutter
    assert solution.exposure_s == EXPOSURE_S
    # the detections are the fitted streaks (matches.det_index indexes them): at the stars' mid-exposure positions
    found, rows = solution.detections, solution.matches.det_index
    assert len(found) == len(solution.streaks) and not np.any(found.is_point_source)
    predicted = np.stack(CAMERA.vector_to_pixel(solution.rot_cam_from_icrs.apply(solution.matches.cat_vectors)), axis=1)
    assert np.max(np.hypot(found.x[rows] - predicted[:, 0], found.y[rows] - predicted[:, 1])) < 2.0  # px
    # one frame cannot order the exposure in time: the rate is compared either way round. This
    # frame's 16 streaks fix the roll rate to 0.027 deg/s (1 sigma): 4.2 % of the rate at 3 sigma,
    # so the rate is refused, and the fitted one lies within its claimed uncertainty
    omega = solution.turn_rad / EXPOSURE_S
    omega = omega if np.dot(omega, OMEGA) > 0 else -omega
    sigma = np.sqrt(np.trace(solution.rate.covariance_rad2_s2))
    assert np.linalg.norm(omega - OMEGA) < 3 * sigma
    if solution.rate.ok:
        assert np.linalg.norm(omega - OMEGA) < 0.01 * np.linalg.norm(OMEGA) and axis_error_rad(omega, OMEGA) < 0.5 * DEG
    else:
        assert solution.rate.status.name == "DEGENERATE" and "rate uncertain" in solution.rate.reason


def test_without_an_exposure_the_turn_per_exposure_is_given(smeared):
    solution = solve_image(smeared.image, fov_deg=12.0, epoch=2025.0)
    assert solution.mode == "streak" and solution.solved and np.isnan(solution.t_mid_s)
    turn = solution.turn_rad if np.dot(solution.turn_rad, OMEGA) > 0 else -solution.turn_rad
    assert np.linalg.norm(turn - OMEGA * EXPOSURE_S) < 0.03 * np.linalg.norm(OMEGA) * EXPOSURE_S
    assert solution.rate.status.name == "DEGENERATE" and "exposure time is unknown" in solution.rate.reason


def test_startrack_solve_says_it_solved_from_streaks(smeared, tmp_path, capsys):
    # The CLI on a FITS frame with EXPTIME: JSON and the table say "streak", the mid-exposure time and the rate.
    import json

    from startrack.cli import main
    from startrack.io import write_fits

    path = tmp_path / "smeared.fits"
    write_fits(path, np.asarray(smeared.image), header={"EXPTIME": EXPOSURE_S})
    assert main(["solve", str(path), "--fov-deg", "12", "--epoch", "2025.0", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["mode"] == "streak" and data["t_mid_s"] == pytest.approx(EXPOSURE_S / 2)
    assert data["exposure_s"] == EXPOSURE_S and data["rate_status"] in ("ok", "degenerate")
    rate = np.radians(data["rate_deg_s"])
    rate = rate if np.dot(rate, OMEGA) > 0 else -rate  # one frame cannot order the exposure in time
    assert np.linalg.norm(rate - OMEGA) < 0.05 * np.linalg.norm(OMEGA)  # within 5 % (rad/s) of the truth
    assert main(["solve", str(path), "--fov-deg", "12", "--epoch", "2025.0"]) == 0
    table = capsys.readouterr().out
    assert "solved from their streaks" in table and "0.1000 s after the exposure starts" in table


def test_the_epoch_of_a_streaked_frame_is_the_one_solve_image_resolved(smeared):
    # DATE-OBS in the header and no epoch given: the streak solution names the header, as a point solve would.
    image = Image(np.asarray(smeared.image), header={"EXPTIME": EXPOSURE_S, "DATE-OBS": "2025-01-01T00:00:00"})
    solution = solve_image(image, fov_deg=12.0)
    assert solution.mode == "streak" and solution.solved
    assert solution.epoch_source == "DATE-OBS" and solution.epoch_jyear == pytest.approx(2025.0, abs=0.01)  # years
    given = solve_image(image, fov_deg=12.0, epoch=2025.0)
    assert given.epoch_source == "given"
