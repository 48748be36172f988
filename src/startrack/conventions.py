"""The conventions every startrack module keeps (DESIGN.md section 3), in one place.

Pixels
    0-based, integer coordinates at pixel centres: the centre of the top-left pixel is (0, 0)
    and its top-left corner is (-0.5, -0.5). Positions are (x, y) = (column, row); images are
    indexed ``image[y, x]``. FITS and astrometry.net put that centre at (1, 1); tetra3 and
    cedar-solve at (0.5, 0.5) in (y, x) order. Convert at the boundary with the helpers below.

Camera frame
    +z is the boresight (out of the lens, towards the sky), +x along increasing image x,
    +y along increasing image y; right-handed. A star at camera vector v lands at
    ``x = cx + fx * v_x / v_z``, ``y = cy + fy * v_y / v_z`` before distortion.

Attitude
    ``scipy.spatial.transform.Rotation`` named for what it maps: ``rot_cam_from_icrs.apply(v)``
    turns ICRS unit vectors into camera-frame vectors. Quaternions appear only in files and CLI
    output as columns ``qx, qy, qz, qw`` (scalar last, the order scipy uses).

RA / Dec / roll (an output format, defined in :mod:`startrack.frames`)
    RA and Dec of the boresight; roll is the angle from celestial north to the image "up"
    direction (towards row 0), measured westward, i.e. ``roll = -PA(up) mod 360`` where PA is
    the position angle east of north. This equals the roll that tetra3 / cedar-solve report.

Units
    Radians and seconds inside; a public name in another unit carries it (``fov_deg``,
    ``sigma_px``, ``err_arcsec``).

Time
    ``astropy.time.Time`` at the public boundary; catalog epochs as Julian years (TDB).
"""

from __future__ import annotations

import numpy as np

FITS_PIXEL_OFFSET: float = 1.0
"""Add to our coordinates to get FITS / astrometry.net 1-based pixel coordinates."""

TETRA3_PIXEL_OFFSET: float = 0.5
"""Add to our coordinates to get tetra3 / cedar-solve coordinates (which are in (y, x) order)."""


def to_fits_pixels(x, y):
    """Our 0-based (x, y) to FITS 1-based (x, y)."""
    return np.asarray(x) + FITS_PIXEL_OFFSET, np.asarray(y) + FITS_PIXEL_OFFSET


def from_fits_pixels(x, y):
    """FITS 1-based (x, y) to our 0-based (x, y)."""
    return np.asarray(x) - FITS_PIXEL_OFFSET, np.asarray(y) - FITS_PIXEL_OFFSET


def to_tetra3_yx(x, y):
    """Our (x, y) to a tetra3 / cedar-solve (N, 2) array of (y, x) centroids."""
    return np.column_stack([np.asarray(y) + TETRA3_PIXEL_OFFSET, np.asarray(x) + TETRA3_PIXEL_OFFSET])
