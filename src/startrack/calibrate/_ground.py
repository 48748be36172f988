"""Photos taken from the ground: when (EXIF / FITS headers), where (a :class:`~.sites.Site`), where the
camera pointed in altitude / azimuth, and the atmosphere (Fowler 2013 Ch. 2 and 5).

The horizon frame is east, north, up (ENU). ``rotation_enu_from_icrs`` is the IAU 2006/2000A
celestial-to-terrestrial rotation (``erfa.c2t06a``: precession-nutation, Earth rotation angle from
UT1; polar motion neglected, < 0.3 arcsec) followed by the site's ENU axes. UT1 comes from the IERS
table astropy ships, read offline; outside it UT1 = UTC is used (|UT1 - UTC| < 0.9 s, i.e. at most
13.5 arcsec of azimuth), with a warning-free fallback documented here. Directions on ICRS axes are
the geocentric apparent ones (:mod:`._apparent`); diurnal aberration (0.3 arcsec) and the site's
parallax for stars are neglected.

Refraction (:mod:`._refraction`) is applied in this frame: catalog directions are raised to where the
camera sees them (``refract_icrs``), or observed directions lowered back (``unrefract_icrs``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

import erfa
import numpy as np
from astropy.time import Time, TimeDelta
from astropy.utils import iers
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from . import _refraction as refraction
from ._sites import Site

_EXIF_TIME = re.compile(r"^\s*(\d{4}):(\d{2}):(\d{2})[ T](\d{2}):(\d{2}):(\d{2})")
_OFFSET = re.compile(r"^\s*([+-])(\d{2}):?(\d{2})\s*$")


def time_from_header(header: Mapping[str, Any], *, utc_offset_hours: float | None = None,
                     mid_exposure: bool = True) -> Time:
    """UTC time of an image from its header (``startrack.io.Image.header``).

    FITS: ``DATE-OBS`` (UTC, ISO 8601; a date-only value takes ``TIME-OBS`` or ``UT``). EXIF:
    ``DateTimeOriginal`` (the camera clock, no zone) plus ``SubsecTimeOriginal``, converted with
    ``OffsetTimeOriginal`` when the camera wrote it, else with ``utc_offset_hours`` (the camera
    clock's offset from UTC, e.g. -6 for MDT), which then must be given. With ``mid_exposure`` the
    time is moved to the middle of the exposure (FITS ``EXPTIME``/``EXPOSURE``, EXIF
    ``ExposureTime``; ``DATE-OBS`` and EXIF times mark the start).

    Raises
    ------
    InvalidInputError
        When no time can be read (no card, or one that is not a date, such as the
        ``0000:00:00 00:00:00`` of a camera whose clock was never set), or an EXIF time has no zone
        and ``utc_offset_hours`` is None.
    """
    if "DATE-OBS" in header:
        start = _fits_time(header)
        exposure = header.get("EXPTIME", header.get("EXPOSURE"))
    elif "DateTimeOriginal" in header or "DateTime" in header:
        start = _exif_time(header, utc_offset_hours)
        exposure = header.get("ExposureTime")
    else:
        raise InvalidInputError("the header has no DATE-OBS (FITS) or DateTimeOriginal (EXIF); give the time")
    if mid_exposure and exposure is not None:
        start = start + TimeDelta(0.5 * float(exposure), format="sec")
    return start


def _fits_time(header: Mapping[str, Any]) -> Time:
    text = str(header["DATE-OBS"]).strip()
    if "T" not in text and ("TIME-OBS" in header or "UT" in header):
        text = f"{text}T{str(header.get('TIME-OBS', header.get('UT'))).strip()}"
    try:
        return Time(text, format="isot" if "T" in text else "iso", scale="utc")
    except ValueError as exc:
        raise InvalidInputError(f"DATE-OBS {text!r} is not an ISO 8601 time") from exc


def _exif_time(header: Mapping[str, Any], utc_offset_hours: float | None) -> Time:
    key = "DateTimeOriginal" if "DateTimeOriginal" in header else "DateTime"
    text = str(header[key])
    m = _EXIF_TIME.match(text)
    if not m:
        raise InvalidInputError(f"EXIF {key} {text!r} is not 'YYYY:MM:DD HH:MM:SS'; give the time")
    y, mo, d, h, mi, s = m.groups()
    sub = str(header.get("SubsecTimeOriginal", "")).strip()
    frac = f".{sub}" if sub.isdigit() else ""
    try:
        local = Time(f"{y}-{mo}-{d}T{h}:{mi}:{s}{frac}", format="isot", scale="utc")
    except ValueError:  # ERFA's "bad month" etc.: cameras write 0000:00:00 00:00:00 when their clock was never set
        raise InvalidInputError(f"EXIF {key} {text!r} is not a date (a camera clock never set?); "
                                "give the time") from None
    offset = _exif_offset_hours(header.get("OffsetTimeOriginal"))
    if offset is None:
        offset = utc_offset_hours
    if offset is None:
        raise InvalidInputError("the EXIF time has no time zone (no OffsetTimeOriginal): give utc_offset_hours, "
                                "the camera clock's offset from UTC")
    return local - TimeDelta(float(offset) * 3600.0, format="sec")


def _exif_offset_hours(value) -> float | None:
    m = _OFFSET.match(str(value)) if value is not None else None
    if not m:
        return None
    sign = -1.0 if m.group(1) == "-" else 1.0
    return sign * (int(m.group(2)) + int(m.group(3)) / 60.0)


def _ut1(time: Time) -> Time:
    """UT1 from astropy's bundled IERS table (offline); UTC outside it."""
    try:
        with iers.conf.set_temp("auto_download", False), iers.conf.set_temp("iers_degraded_accuracy", "error"):
            return time.ut1
    except (iers.IERSRangeError, ValueError, IndexError):
        return Time(time.utc.jd1, time.utc.jd2, format="jd", scale="ut1")


def rotation_enu_from_itrs(site: Site) -> Rotation:
    """Rotation from Earth-fixed (ITRS) axes to the site's east, north, up axes."""
    lat, lon = math.radians(site.latitude_deg), math.radians(site.longitude_deg)
    east = [-math.sin(lon), math.cos(lon), 0.0]
    north = [-math.sin(lat) * math.cos(lon), -math.sin(lat) * math.sin(lon), math.cos(lat)]
    up = [math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)]
    return Rotation.from_matrix(np.array([east, north, up]))


def rotation_enu_from_icrs(time: Time, site: Site) -> Rotation:
    """``rot_enu_from_icrs`` at ``time`` for ``site`` (module docstring)."""
    if not isinstance(time, Time) or not time.isscalar:
        raise InvalidInputError(f"time must be a scalar astropy Time, got {time!r}")
    tt, ut1 = time.tt, _ut1(time)
    c2t = erfa.c2t06a(tt.jd1, tt.jd2, ut1.jd1, ut1.jd2, 0.0, 0.0)
    return rotation_enu_from_itrs(site) * Rotation.from_matrix(c2t)


def altaz_from_vectors(vectors_enu: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Altitude and azimuth (radians; azimuth from north through east, in [0, 2 pi)) of ENU vectors."""
    v = np.asarray(vectors_enu, float)
    alt = np.arctan2(v[..., 2], np.hypot(v[..., 0], v[..., 1]))
    az = np.mod(np.arctan2(v[..., 0], v[..., 1]), 2 * np.pi)
    return alt, az


def pointing_altaz(rot_cam_from_icrs: Rotation, time: Time, site: Site, *,
                   refracted: bool = True) -> tuple[float, float]:
    """Altitude and azimuth (degrees) of the camera's optical axis.

    ``refracted`` (default): the apparent altitude, where the camera physically points, which is
    the true altitude of the sky at the centre of the image plus refraction.
    """
    axis_icrs = rot_cam_from_icrs.inv().apply([0.0, 0.0, 1.0])
    enu = rotation_enu_from_icrs(time, site).apply(axis_icrs)
    if refracted:
        enu = refraction.refract(enu, site.temperature_c, site.pressure)
    alt, az = altaz_from_vectors(enu)
    return math.degrees(float(alt)), math.degrees(float(az))


def rotation_cam_from_enu(rot_cam_from_icrs: Rotation, time: Time, site: Site) -> Rotation:
    """The camera attitude relative to the local horizon (Fowler 2013 eq. 7.17's camera -> ENU)."""
    return rot_cam_from_icrs * rotation_enu_from_icrs(time, site).inv()


def refract_icrs(vectors_icrs: ArrayLike, time: Time, site: Site) -> NDArray[np.float64]:
    """Catalog (apparent, unrefracted) directions (N, 3) -> where they appear through the
    atmosphere, still on ICRS axes: solve against these to get the camera's true attitude."""
    rot = rotation_enu_from_icrs(time, site)
    return rot.inv().apply(refraction.refract(rot.apply(vectors_icrs), site.temperature_c, site.pressure))


def unrefract_icrs(vectors_icrs: ArrayLike, time: Time, site: Site) -> NDArray[np.float64]:
    """Observed directions (N, 3, on ICRS axes through a preliminary attitude) -> refraction
    removed (lowered towards the horizon; Fowler 2013 Ch.5 with the sign erratum fixed)."""
    rot = rotation_enu_from_icrs(time, site)
    return rot.inv().apply(refraction.unrefract(rot.apply(vectors_icrs), site.temperature_c, site.pressure))
