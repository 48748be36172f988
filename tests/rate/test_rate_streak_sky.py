"""The sky under the streaks (startrack.rate._streak_sky): a sloping sky no longer hides a smeared
frame's streaks from the search, and a flat one is searched as before."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.frames import attitude_error
from startrack.rate import solve_streaked
from startrack.rate._streak_find import find_streak_candidates
from startrack.rate._streak_sky import block_sky, sloped_sky
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(1024, 1024, 12.0)
OMEGA = 2.0 * DEG * np.array([0.3, -0.9, 0.2]) / np.linalg.norm([0.3, -0.9, 0.2])
STREAK_PX = 33.0  # the streaks' length on this frame (0.2 s at 2 deg/s, 85 arcsec px): 32-35 px fitted
YY, XX = np.mgrid[0:1024, 0:1024]


@pytest.fixture(scope="module")
def smeared():
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.2)
    return simulate_frame(CAMERA, Rotation.from_euler("zyx", [40, 20, 10], degrees=True), max_mag=7.5,
                          epoch_jyear=2025.0, sensor=sensor, rng=1, rate_rad_s=OMEGA)


def with_light(frame, light: np.ndarray) -> np.ndarray:
    """The frame with stray light ``light`` (e- per pixel, shape of the frame) and its shot noise
    (generic-cmos: 1 e- per ADU, so added to the counts as they are)."""
    return np.clip(frame.image + np.random.default_rng(2).poisson(light), 0, 65535).astype(frame.image.dtype)


def test_a_plane_is_recovered_to_the_edges():
    rng = np.random.default_rng(0)
    ny, nx = 200, 256
    plane = 50.0 + 0.8 * np.arange(nx)[None, :] - 0.5 * np.arange(ny)[:, None]  # counts per block
    sky = block_sky(plane + rng.normal(0.0, 4.0, (ny, nx)))
    # the medians of the 32-block edge strips carry 1.25 x 4 / sqrt(32) = 0.9 counts of noise
    assert np.max(np.abs(sky - plane)) < 4.0  # counts per block, of a plane spanning 300
    assert sloped_sky(plane + rng.normal(0.0, 4.0, (ny, nx)), 4.0) is not None
    assert sloped_sky(50.0 + rng.normal(0.0, 4.0, (ny, nx)), 4.0) is None


def test_a_flat_frame_is_searched_about_its_one_level(smeared):
    found = find_streak_candidates(smeared.image)
    assert len(found) >= 8 and np.all(found.sky == found.background)


@pytest.mark.parametrize(("light", "least"), [("ramp", 2), ("limb", 5)])
def test_streaks_are_found_under_a_sloping_sky_and_no_strip_of_it(smeared, light, least):
    """Before: 0 candidates under the ramp and 1 under the limb (the sky's slope set the threshold);
    9 without them. The ramp's shot noise (up to 1.7 times the sky's) leaves the faint ones under it."""
    glow = 200.0 * XX / 1023.0 if light == "ramp" else 200.0 * np.exp(-(1023 - YY) / 150.0)  # e-
    found = find_streak_candidates(with_light(smeared, glow))
    assert len(found) >= least
    assert np.all(found.length_px < 3 * STREAK_PX)  # px: streaks, not the edge of the light (970-1010 px)
    truth = glow[found.centroid_xy[:, 1].astype(int), found.centroid_xy[:, 0].astype(int)]
    assert np.all(np.abs(found.sky - np.median(smeared.image) - truth) < 10.0)  # e- per pixel, of up to 200


@pytest.mark.parametrize("euler_deg", [(40, 20, 10), (100, -30, 50), (200, 45, -20)])
def test_frames_under_limb_glow_are_solved_from_their_streaks(euler_deg):
    """300 e- of glow at the bottom edge, falling by e over 150 px. Before: TOO_FEW_STARS on all
    three (1-2 candidates; 9-13 without the glow)."""
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.2)
    frame = simulate_frame(CAMERA, Rotation.from_euler("zyx", euler_deg, degrees=True), max_mag=7.5,
                           epoch_jyear=2025.0, sensor=sensor, rng=1, rate_rad_s=OMEGA)
    solution = solve_streaked(with_light(frame, 300.0 * np.exp(-(1023 - YY) / 150.0)), fov_deg=12.0, epoch=2025.0)
    assert solution.solved, solution.reason
    assert attitude_error(frame.truth.rot_cam_from_icrs, solution.rot_cam_from_icrs) < CAMERA.pixel_scale_arcsec \
        * ARCSEC  # within a pixel of the mid-exposure attitude
