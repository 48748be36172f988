"""Shared fixtures for the simulator tests: a small camera, a simple sensor, a fixed attitude."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.camera import Camera
from startrack.frames import rotation_from_radec_roll
from startrack.simulate import Detector, Optics, Sensor
from startrack.units import DEG


@pytest.fixture
def small_camera() -> Camera:
    """A 96 x 80 pinhole camera with a 4 deg horizontal field."""
    return Camera.from_fov(96, 80, 4.0, name="test-small")


@pytest.fixture
def rot():
    """An arbitrary attitude (away from the poles and RA 0)."""
    return rotation_from_radec_roll(123.4 * DEG, -31.0 * DEG, 17.0 * DEG)


@pytest.fixture
def plain_sensor() -> Sensor:
    """1 cm^2, QE 0.5, 16 bits, gain 2, read noise 5 e-, dark 50 e-/s, bias 100 ADU, t = 1 s."""
    return Sensor(optics=Optics(aperture_area_m2=1e-4, psf_sigma_px=1.5),
                  detector=Detector(quantum_efficiency=0.5, gain_e_per_adu=2.0, read_noise_e=5.0,
                                    dark_current_e_s=50.0, bias_adu=100.0, full_well_e=1e5,
                                    bit_depth=16),
                  exposure_s=1.0)


@pytest.fixture
def vectors_at():
    """A function giving the ICRS unit vectors (N, 3) that land on pixels (x, y)."""

    def make(camera: Camera, rot_cam_from_icrs, x, y) -> np.ndarray:
        return rot_cam_from_icrs.inv().apply(camera.pixel_to_vector(np.asarray(x), np.asarray(y)))

    return make
