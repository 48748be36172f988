"""Calibration and corrections: camera intrinsics and distortion from stars or a checkerboard,
apparent place (proper motion, parallax, aberration, light deflection, precession-nutation),
atmospheric refraction, ground-based photos, fixed-mount repeatability (DESIGN.md §2).

Modules
-------
stars          joint multi-frame calibration of intrinsics, distortion and attitudes (robust LSQ)
lens_models    Brown-Conrady parameterisation for the fit; distortion fields
tilted_ccd     Jacobs 1995's tilted-CCD plus cubic radial model
quick          Jacobs 1995's single-pair focal length and rotation-based optical centre
selfcal        solve, calibrate, re-solve from an uncalibrated camera
bench          checkerboard calibration with OpenCV (Fowler 2013)
apparent       catalog (ICRS, epoch) -> apparent directions; true equator and equinox of date
bodies         variable stars and the Sun, Moon and bright planets near the field
refraction     Bennett / Saemundsson refraction in the horizon frame
sites, ground  observing sites, time from EXIF / FITS, alt/az of the pointing
repeatability  fixed-mount repeatability analysis (Fowler 2013 Ch. 7 and 9)
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "CircularOrbit": ".apparent",
    "aberrate": ".apparent",
    "aberration_angle_rad": ".apparent",
    "apparent_vectors": ".apparent",
    "attitude_in_true_of_date": ".apparent",
    "earth_state": ".apparent",
    "observer_state": ".apparent",
    "Checkerboard": ".bench",
    "calibrate_checkerboard": ".bench",
    "find_corners": ".bench",
    "render_checkerboard": ".bench",
    "bright_bodies_near": ".bodies",
    "variable_flags": ".bodies",
    "altaz_from_vectors": ".ground",
    "pointing_altaz": ".ground",
    "refract_icrs": ".ground",
    "rotation_enu_from_icrs": ".ground",
    "time_from_header": ".ground",
    "unrefract_icrs": ".ground",
    "solve_ground_photo": ".ground_solve",
    "distortion_field_px": ".lens_models",
    "centre_from_rotation": ".quick",
    "focal_from_pair": ".quick",
    "focal_from_stars": ".quick",
    "refract": ".refraction",
    "unrefract": ".refraction",
    "Repeatability": ".repeatability",
    "error_budget": ".repeatability",
    "affordable_fit": ".selfcal",
    "justified": ".selfcal",
    "pinhole_of": ".selfcal",
    "self_calibrate": ".selfcal",
    "Site": ".sites",
    "get_site": ".sites",
    "load_sites": ".sites",
    "save_site": ".sites",
    "CalibrationFrame": ".stars",
    "DEFAULT_FIT": ".stars",
    "calibrate_from_stars": ".stars",
    "TiltedCcdCamera": ".tilted_ccd",
    "TiltedCcdModel": ".tilted_ccd",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
