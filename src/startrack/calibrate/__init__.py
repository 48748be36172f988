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
