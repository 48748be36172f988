"""Unit constants and small converters.

Everything inside startrack is in radians and seconds. Multiply by a constant to go *into*
radians, divide to come out: ``5 * ARCSEC`` is five arcseconds in radians and
``angle_rad / ARCSEC`` is that angle in arcseconds.
"""

from __future__ import annotations

import math

RAD: float = 1.0
DEG: float = math.pi / 180.0
ARCMIN: float = DEG / 60.0
ARCSEC: float = DEG / 3600.0
MAS: float = ARCSEC / 1000.0

SECOND: float = 1.0
MILLISECOND: float = 1e-3

PIXEL: float = 1.0
"""One pixel, for tolerances written as ``0.05 * PIXEL``."""

JULIAN_YEAR_S: float = 365.25 * 86400.0
J2000_JD: float = 2451545.0
HIPPARCOS_EPOCH_JYEAR: float = 1991.25


def deg(x):
    """Degrees to radians (scalar or array)."""
    return x * DEG


def to_deg(x):
    """Radians to degrees (scalar or array)."""
    return x / DEG


def to_arcsec(x):
    """Radians to arcseconds (scalar or array)."""
    return x / ARCSEC
