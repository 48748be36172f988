"""Star-camera simulation: radiometry, optics, detector, motion and streaks, satellites, sequences,
each frame with its truth; and the analytic formulas the simulator must agree with.

Modules
-------
radiometry  magnitude -> electrons with a physical V-band zero point; Optics, Detector, Sensor
passband    spectral response and the colour (B - V) factor of a star in a non-V band
background  sky background (zodiacal light) and stray light per pixel
optics      field curvature, vignetting, the Airy PSF
psf         pixel-integrated Gaussian PSF stamps
detector    fixed pattern (PRNU, DSNU, hot and dead pixels) and blooming
noise       shot, dark, read noise, gain, bias, quantisation, saturation (each switchable)
motion      quaternion kinematics and attitude profiles (hold, slew, tumble, varying, recorded)
streaks     light integrated along each source's path over sub-steps; rolling shutter
sampling    where sources are during the exposure, and which reach the image
orbits      two-body + J2 orbits, Earth shadow, Sun and Moon (astropy built-in ephemeris)
rso         satellites, their magnitudes and lines of sight; Sun / Moon / Earth flags
scene       render_stars: point sources + attitude (profile) -> SimulatedImage (image + Truth)
sky         simulate_frame: Hipparcos stars in the field of a camera
sequence    simulate_sequence: a stream of frames over an attitude profile
snr         analytic SNR, limiting magnitude, smear-limited rate
starcount   expected number of stars in the field; magnitude limit for a minimum everywhere

Example
-------
>>> from startrack import get_preset
>>> from startrack.simulate import random_attitude, simulate_frame
>>> sim = simulate_frame(get_preset("far-mst"), random_attitude(1), rng=2)  # doctest: +SKIP
>>> sim.image.shape, sim.truth.ids[:3]                                       # doctest: +SKIP
"""

from __future__ import annotations

from .background import SkyBackground, zodiacal_mag_arcsec2
from .detector import PixelMaps, pixel_maps
from .motion import (
    ConstantRate,
    RecordedProfile,
    Slew,
    VaryingRate,
    inertial_hold,
    tumble,
)
from .noise import NoiseModel, read_out
from .orbits import KeplerElements, Orbit, in_earth_shadow, sun_moon_km
from .passband import PASSBANDS, Passband
from .profile_file import load_profile, save_profile
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
from .rso import RSO, BrightBodyFlags, OrbitalScene, Snapshot
from .scene import (
    FrameTiming,
    SimulatedImage,
    Truth,
    field_radius_rad,
    project_stars,
    random_attitude,
    render_stars,
)
from .sequence import frame_rng, simulate_sequence
from .sky import DEFAULT_MAX_MAG, SkyModel, simulate_frame
from .snr import limiting_magnitude, max_rate_rad_s, peak_snr, star_snr
from .starcount import expected_star_count
from .truth import RSOTruth

__all__ = [
    "DEFAULT_MAX_MAG",
    "PASSBANDS",
    "RSO",
    "SEED000_EQ34_ZERO_POINT_PHOTONS_S_M2",
    "SENSOR_PRESETS",
    "V_MAG0_PHOTONS_S_M2",
    "BrightBodyFlags",
    "ConstantRate",
    "Detector",
    "FrameTiming",
    "KeplerElements",
    "NoiseModel",
    "Optics",
    "Orbit",
    "OrbitalScene",
    "Passband",
    "PixelMaps",
    "RSOTruth",
    "RecordedProfile",
    "Sensor",
    "SimulatedImage",
    "SkyBackground",
    "SkyModel",
    "Slew",
    "Snapshot",
    "Truth",
    "VaryingRate",
    "electrons_from_magnitude",
    "expected_star_count",
    "field_radius_rad",
    "frame_rng",
    "get_sensor_preset",
    "in_earth_shadow",
    "inertial_hold",
    "limiting_magnitude",
    "load_profile",
    "magnitude_from_electrons",
    "max_rate_rad_s",
    "peak_snr",
    "photon_flux_from_magnitude",
    "pixel_maps",
    "project_stars",
    "random_attitude",
    "read_out",
    "render_gaussian_psf",
    "render_stars",
    "save_profile",
    "simulate_frame",
    "simulate_sequence",
    "star_snr",
    "sun_moon_km",
    "tumble",
    "zodiacal_mag_arcsec2",
]
