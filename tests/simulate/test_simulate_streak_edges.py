"""Streaks of stars that reach the image but sit beyond the field's edge at mid-exposure."""

import numpy as np
import pytest

from startrack import Camera
from startrack.frames import random_rotations
from startrack.simulate import get_sensor_preset, simulate_frame

CAMERA = Camera.from_fov(1024, 1024, 20.0)


@pytest.mark.parametrize("seed", [0, 3, 4])
def test_long_streaks_crossing_the_edge_render_with_finite_light(seed):
    # 0.05 rad/s for 1.2 s sweeps 3.4 deg, 17 % of the field: some stars enter or leave the image
    # while their mid-exposure direction is outside the projectable field (these frames failed).
    sensor = get_sensor_preset("generic-cmos").with_exposure(1.2)
    sim = simulate_frame(CAMERA, random_rotations(None, rng=seed), max_mag=7.0, sensor=sensor, rng=seed,
                         rate_rad_s=(0.0, 0.05, 0.0), noise=False)
    assert np.all(np.isfinite(sim.image))
    assert np.all(np.isfinite(sim.truth.electrons)) and np.all(sim.truth.electrons > 0)
    streak_px = np.hypot(sim.truth.x_end - sim.truth.x_start, sim.truth.y_end - sim.truth.y_start)
    assert np.nanmedian(streak_px) > 0.15 * CAMERA.width
