"""A short simulated slew for the tracker tests: rest, speed up to 8 deg/s, hold, slow down, rest."""

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.simulate import VaryingRate, get_sensor_preset, simulate_sequence
from startrack.units import DEG

CAMERA = Camera.from_fov(512, 512, 20.0)
EXPOSURE_S = 0.1
FRAME_RATE_HZ = 2.5
PEAK = 8.0 * DEG
AXIS = np.array([0.3, -0.9, 0.2]) / np.linalg.norm([0.3, -0.9, 0.2])


def slew_rate(t_s):
    """Rest 0.4 s, speed up to 8 deg/s in 1.6 s, hold 0.4 s, slow down in 1.6 s, rest (rad/s, (N, 3))."""
    t = np.asarray(t_s, dtype=float) - 0.4
    speed = PEAK * np.clip(np.minimum(t / 1.6, (3.6 - t) / 1.6), 0.0, 1.0)
    return speed[:, None] * AXIS[None, :]


def simulate_slew(n_frames: int = 12) -> list:
    """The slew's frames (SimulatedImage, 512 x 512, 20 deg, generic CMOS, 0.1 s at 2.5 frames a second)."""
    profile = VaryingRate(Rotation.from_euler("zyx", [40, 20, 10], degrees=True), slew_rate)
    sensor = get_sensor_preset("generic-cmos").with_exposure(EXPOSURE_S)
    return list(simulate_sequence(CAMERA, profile, n_frames, frame_rate_hz=FRAME_RATE_HZ, sensor=sensor, seed=3,
                                  max_mag=7.5, catalog_epoch_jyear=2025.0))
