"""Star-image simulation: radiometry, PSF rendering, detector noise, scenes with truth.

Modules
-------
radiometry  magnitude -> electrons with a physical V-band zero point; Optics, Detector, Sensor
psf         pixel-integrated Gaussian PSF stamps, scatter-added into an image
noise       shot, dark, read noise, gain, bias, quantisation, saturation (each switchable)
scene       render_stars (arrays in) -> SimulatedImage (image + Truth); random_attitude
sky         simulate_frame: Hipparcos stars in the field of a camera at an attitude

Example
-------
>>> from startrack import get_preset
>>> from startrack.simulate import random_attitude, simulate_frame
>>> sim = simulate_frame(get_preset("far-mst"), random_attitude(1), rng=2)  # doctest: +SKIP
>>> sim.image.shape, sim.truth.ids[:3]                                       # doctest: +SKIP
"""

from __future__ import annotations

from .noise import NoiseModel, read_out
from .psf import render_gaussian_psf
from .radiometry import (
    SEED000_EQ34_ZERO_POINT_PHOTONS_S_M2,
    SENSOR_PRESETS,
    V_MAG0_PHOTONS_S_M2,
    Detector,
    Optics,
    Sensor,
    electrons_from_magnitude,
    get_sensor_preset,
    magnitude_from_electrons,
    photon_flux_from_magnitude,
)
from .scene import (
    SimulatedImage,
    Truth,
    field_radius_rad,
    project_stars,
    random_attitude,
    render_stars,
)
from .sky import DEFAULT_MAX_MAG, SkyModel, simulate_frame

__all__ = [
    "DEFAULT_MAX_MAG",
    "SEED000_EQ34_ZERO_POINT_PHOTONS_S_M2",
    "SENSOR_PRESETS",
    "V_MAG0_PHOTONS_S_M2",
    "Detector",
    "NoiseModel",
    "Optics",
    "Sensor",
    "SimulatedImage",
    "SkyModel",
    "Truth",
    "electrons_from_magnitude",
    "field_radius_rad",
    "get_sensor_preset",
    "magnitude_from_electrons",
    "photon_flux_from_magnitude",
    "project_stars",
    "random_attitude",
    "read_out",
    "render_gaussian_psf",
    "render_stars",
    "simulate_frame",
]
