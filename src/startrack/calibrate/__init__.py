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

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._apparent import (
        CircularOrbit,
        aberrate,
        aberration_angle_rad,
        apparent_vectors,
        attitude_in_true_of_date,
        earth_state,
        observer_state,
    )
    from ._bench import Checkerboard, calibrate_checkerboard, find_corners, render_checkerboard
    from ._bodies import bright_bodies_near, variable_flags
    from ._ground import (
        altaz_from_vectors,
        pointing_altaz,
        refract_icrs,
        rotation_enu_from_icrs,
        time_from_header,
        unrefract_icrs,
    )
    from ._ground_solve import solve_ground_photo
    from ._lens_models import distortion_field_px
    from ._quick import centre_from_rotation, focal_from_pair, focal_from_stars
    from ._refraction import refract, unrefract
    from ._repeatability import Repeatability, error_budget, repeatability
    from ._selfcal import affordable_fit, justified, pinhole_of, self_calibrate
    from ._sites import Site, get_site, load_sites, save_site
    from ._stars import DEFAULT_FIT, CalibrationFrame, calibrate_from_stars
    from ._tilted_ccd import TiltedCcdCamera, TiltedCcdModel

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
