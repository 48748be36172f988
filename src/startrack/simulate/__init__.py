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

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "SkyBackground": ".background",
    "zodiacal_mag_arcsec2": ".background",
    "PixelMaps": ".detector",
    "pixel_maps": ".detector",
    "ConstantRate": ".motion",
    "RecordedProfile": ".motion",
    "Slew": ".motion",
    "VaryingRate": ".motion",
    "inertial_hold": ".motion",
    "tumble": ".motion",
    "NoiseModel": ".noise",
    "read_out": ".noise",
    "readout_table": ".noise",
    "psf_sigma_px": ".optics",
    "KeplerElements": ".orbits",
    "MU_EARTH_KM3_S2": ".orbits",
    "Orbit": ".orbits",
    "R_EARTH_KM": ".orbits",
    "R_MOON_KM": ".orbits",
    "R_SUN_KM": ".orbits",
    "in_earth_shadow": ".orbits",
    "sun_moon_km": ".orbits",
    "PASSBANDS": ".passband",
    "Passband": ".passband",
    "load_profile": ".profile_file",
    "save_profile": ".profile_file",
    "add_stamps": ".psf",
    "render_gaussian_psf": ".psf",
    "Detector": ".radiometry",
    "Optics": ".radiometry",
    "SEED000_EQ34_ZERO_POINT_PHOTONS_S_M2": ".radiometry",
    "SENSOR_PRESETS": ".radiometry",
    "Sensor": ".radiometry",
    "V_MAG0_PHOTONS_S_M2": ".radiometry",
    "electrons_from_magnitude": ".radiometry",
    "get_sensor_preset": ".radiometry",
    "magnitude_from_electrons": ".radiometry",
    "photon_flux_from_magnitude": ".radiometry",
    "rig_star_lists": ".rig",
    "simulate_rig": ".rig",
    "BrightBodyFlags": ".rso",
    "OrbitalScene": ".rso",
    "RSO": ".rso",
    "Snapshot": ".rso",
    "FrameTiming": ".scene",
    "field_radius_rad": ".scene",
    "project_stars": ".scene",
    "psf_radius_px": ".scene",
    "random_attitude": ".scene",
    "render_stars": ".scene",
    "frame_rng": ".sequence",
    "simulate_sequence": ".sequence",
    "DEFAULT_MAX_MAG": ".sky",
    "SkyModel": ".sky",
    "simulate_frame": ".sky",
    "limiting_magnitude": ".snr",
    "max_rate_rad_s": ".snr",
    "peak_snr": ".snr",
    "star_snr": ".snr",
    "SplitFieldFrame": ".split_fov",
    "elliptical_stamps": ".split_fov",
    "simulate_split_frame": ".split_fov",
    "expected_star_count": ".starcount",
    "RSOTruth": ".truth",
    "SimulatedImage": ".truth",
    "Truth": ".truth",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
