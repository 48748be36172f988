"""NaN and infinite pixels in a smeared frame (startrack.rate._streak_find.finite_frame): one of
either made the streak path's sky statistics NaN, and ``solve_image`` stopped with exit 3
("cannot convert float NaN to integer") for an infinite pixel, or refused the frame for a NaN one,
where a still frame's detector leaves such pixels out. Found by fuzzing the commands."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera, solve_image
from startrack.errors import InvalidInputError
from startrack.frames import attitude_error
from startrack.rate import find_streaks, solve_streaked
from startrack.rate._streak_find import finite_frame
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(512, 512, 12.0)
OMEGA = 2.0 * DEG * np.array([0.3, -0.9, 0.2]) / np.linalg.norm([0.3, -0.9, 0.2])


@pytest.fixture(scope="module")
def smeared():
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.2)
    return simulate_frame(CAMERA, Rotation.from_euler("zyx", [40, 20, 10], degrees=True), max_mag=8.0,
                          epoch_jyear=2025.0, sensor=sensor, rng=1, rate_rad_s=OMEGA)


def damaged(frame, value: float) -> np.ndarray:
    image = frame.image.astype(np.float32)
    image[0, 0] = value
    image[200:210, 40:140] = value  # a strip of missing pixels
    return image


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_smeared_frame_with_missing_pixels_solves_as_without_them(smeared, value):
    clean = solve_streaked(smeared.image.astype(np.float32), exposure_s=0.2, fov_deg=12.0, epoch=2025.0)
    assert clean.solved
    found = solve_streaked(damaged(smeared, value), exposure_s=0.2, fov_deg=12.0, epoch=2025.0)
    assert found.solved, found.reason
    assert attitude_error(clean.rot_cam_from_icrs, found.rot_cam_from_icrs) < 10 * ARCSEC
    whole = solve_image(damaged(smeared, value), fov_deg=12.0, epoch=2025.0)
    assert whole.solved, whole.reason
    assert len(find_streaks(damaged(smeared, value)).regions) > 0


def test_finite_frame_fills_with_the_median_and_refuses_a_frame_of_no_value():
    image = np.arange(12.0).reshape(3, 4)
    assert finite_frame(image) is image
    image[1, 1] = np.nan
    filled = finite_frame(image)
    assert filled[1, 1] == np.median(np.delete(np.arange(12.0), 5)) and np.isnan(image[1, 1])
    with pytest.raises(InvalidInputError, match="no finite pixel"):
        finite_frame(np.full((3, 4), np.inf))
