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

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._background import SkyBackground, zodiacal_mag_arcsec2
    from ._detector import PixelMaps, pixel_maps
    from ._motion import ConstantRate, RecordedProfile, Slew, VaryingRate, inertial_hold, tumble
    from ._noise import NoiseModel, read_out, readout_table
    from ._optics import psf_sigma_px
    from ._orbits import (
        MU_EARTH_KM3_S2,
        R_EARTH_KM,
        R_MOON_KM,
        R_SUN_KM,
        KeplerElements,
        Orbit,
        in_earth_shadow,
        sun_moon_km,
    )
    from ._passband import PASSBANDS, Passband
    from ._profile_file import load_profile, save_profile
    from ._psf import add_stamps, render_gaussian_psf
    from ._radiometry import (
        HUFFMAN2006_EQ34_ZERO_POINT_PHOTONS_S_M2,
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
    from ._rig import rig_star_lists, simulate_rig
    from ._rso import RSO, BrightBodyFlags, OrbitalScene, Snapshot
    from ._scene import FrameTiming, field_radius_rad, project_stars, psf_radius_px, random_attitude, render_stars
    from ._sequence import frame_rng, simulate_sequence
    from ._sky import DEFAULT_MAX_MAG, SkyModel, simulate_frame
    from ._snr import limiting_magnitude, max_rate_rad_s, peak_snr, star_snr
    from ._split_fov import SplitFieldFrame, elliptical_stamps, simulate_split_frame
    from ._starcount import expected_star_count
    from ._truth import RSOTruth, SimulatedImage, Truth

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
