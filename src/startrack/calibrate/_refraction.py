"""Atmospheric refraction for photographs taken from the ground (Fowler 2013 Ch. 5).

Bennett (1982) gives the refraction R from the *apparent* (observed) altitude h_a (Fowler 2013 eq. 5.1,
Fowler 2013 Ch.5; Meeus, *Astronomical Algorithms*, ch. 16)::

    R [arcmin] = cot(h_a + 7.31 / (h_a + 4.4)) * (P / 101) * (283 / (273 + T))

with h_a and the inner sum in degrees, P in kPa and T in deg C; accurate to 0.07 arcmin (4.2 arcsec)
for 0-90 deg at the standard 10 C and 101.0 kPa. Refraction lifts every star towards the zenith:
``h_a = h_true + R``. Correcting an *observed* direction therefore lowers it by R (the erratum to
Fowler 2013 eq. 5.5: rotate by ``-R`` about ``v x z``, or equivalently ``+R`` about ``z x v``); making a
catalog (true) direction apparent raises it, by the R of the apparent altitude (solved by
iteration, or Saemundsson's formula from the true altitude, consistent with Bennett's to 0.1').

The horizon frame is east, north, up (ENU; +z the zenith). Azimuth is unchanged by refraction.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ..frames import normalize
from ..units import ARCMIN, DEG

STANDARD_TEMPERATURE_C: float = 10.0
STANDARD_PRESSURE_KPA: float = 101.0
BENNETT_ACCURACY_RAD: float = 0.07 * ARCMIN
"""Bennett's stated accuracy, 4.2 arcsec, at the standard conditions (Fowler 2013 Table 9.5)."""
LOWEST_ALTITUDE_RAD: float = -1.0 * DEG
"""Below this the formulas are not meant to be used; altitudes are clipped to it."""


def _scale(temperature_c: float, pressure_kpa: float) -> float:
    t, p = float(temperature_c), float(pressure_kpa)
    if not (math.isfinite(t) and -90.0 < t < 70.0):
        raise InvalidInputError(f"temperature_c must be an air temperature in deg C (-90..70), got {temperature_c!r}")
    if not (math.isfinite(p) and 0.0 <= p < 120.0):
        raise InvalidInputError(f"pressure_kpa must be an air pressure in kPa (0..120), got {pressure_kpa!r}")
    return (p / STANDARD_PRESSURE_KPA) * (283.0 / (273.0 + t))


def bennett_refraction(apparent_altitude_rad: ArrayLike, temperature_c: float = STANDARD_TEMPERATURE_C,
                       pressure_kpa: float = STANDARD_PRESSURE_KPA) -> NDArray[np.float64]:
    """Refraction R (radians) at the given apparent altitudes (radians); Bennett 1982, Fowler 2013 eq. 5.1.

    Altitudes below -1 deg are evaluated at -1 deg; at the zenith R is about -0.08 arcsec (Bennett's
    formula is not forced to zero there).
    """
    h_deg = np.clip(np.asarray(apparent_altitude_rad, float), LOWEST_ALTITUDE_RAD, math.pi / 2) / DEG
    r_arcmin = 1.0 / np.tan((h_deg + 7.31 / (h_deg + 4.4)) * DEG)
    return r_arcmin * ARCMIN * _scale(temperature_c, pressure_kpa)


def saemundsson_refraction(true_altitude_rad: ArrayLike, temperature_c: float = STANDARD_TEMPERATURE_C,
                           pressure_kpa: float = STANDARD_PRESSURE_KPA) -> NDArray[np.float64]:
    """Refraction R (radians) from the *true* altitude (radians): Saemundsson 1986,
    ``R = 1.02 cot(h + 10.3 / (h + 5.11))`` arcmin, with Bennett's T, P scaling."""
    h_deg = np.clip(np.asarray(true_altitude_rad, float), LOWEST_ALTITUDE_RAD - 0.6 * DEG, math.pi / 2) / DEG
    r_arcmin = 1.02 / np.tan((h_deg + 10.3 / (h_deg + 5.11)) * DEG)
    return r_arcmin * ARCMIN * _scale(temperature_c, pressure_kpa)


def apparent_from_true_altitude(true_altitude_rad: ArrayLike, temperature_c: float = STANDARD_TEMPERATURE_C,
                                pressure_kpa: float = STANDARD_PRESSURE_KPA) -> NDArray[np.float64]:
    """Apparent altitude h_a with ``h_a - R_Bennett(h_a) = h_true`` (exact inverse of
    :func:`true_from_apparent_altitude`, by fixed-point iteration; converges to 1e-12 rad)."""
    h = np.asarray(true_altitude_rad, float)
    h_a = h + saemundsson_refraction(h, temperature_c, pressure_kpa)
    for _ in range(20):
        new = h + bennett_refraction(h_a, temperature_c, pressure_kpa)
        if np.all(np.abs(new - h_a) < 1e-12):
            return new
        h_a = new
    return h_a


def true_from_apparent_altitude(apparent_altitude_rad: ArrayLike, temperature_c: float = STANDARD_TEMPERATURE_C,
                                pressure_kpa: float = STANDARD_PRESSURE_KPA) -> NDArray[np.float64]:
    """True (unrefracted) altitude: ``h_a - R_Bennett(h_a)``."""
    h_a = np.asarray(apparent_altitude_rad, float)
    return h_a - bennett_refraction(h_a, temperature_c, pressure_kpa)


def _with_altitude(vectors_enu: NDArray, altitude: NDArray) -> NDArray[np.float64]:
    """Unit vectors with the azimuth of ``vectors_enu`` and the given altitude."""
    horizontal = np.hypot(vectors_enu[..., 0], vectors_enu[..., 1])
    safe = np.where(horizontal > 0, horizontal, 1.0)
    c = np.cos(altitude) / safe
    out = np.stack([vectors_enu[..., 0] * c, vectors_enu[..., 1] * c, np.sin(altitude)], axis=-1)
    return np.where((horizontal > 0)[..., None], out, normalize(vectors_enu))


def altitude_of(vectors_enu: ArrayLike) -> NDArray[np.float64]:
    """Altitude (radians) of ENU vectors (..., 3)."""
    v = np.asarray(vectors_enu, float)
    return np.arctan2(v[..., 2], np.hypot(v[..., 0], v[..., 1]))


def refract(vectors_enu: ArrayLike, temperature_c: float = STANDARD_TEMPERATURE_C,
            pressure_kpa: float = STANDARD_PRESSURE_KPA) -> NDArray[np.float64]:
    """True (catalog) directions (..., 3) in the horizon frame -> apparent ones: raised by R."""
    v = np.asarray(vectors_enu, float)
    return _with_altitude(v, apparent_from_true_altitude(altitude_of(v), temperature_c, pressure_kpa))


def unrefract(vectors_enu: ArrayLike, temperature_c: float = STANDARD_TEMPERATURE_C,
              pressure_kpa: float = STANDARD_PRESSURE_KPA) -> NDArray[np.float64]:
    """Observed (apparent) directions (..., 3) in the horizon frame -> true ones: lowered by R
    (Fowler 2013 Ch.5 step 5 with the sign erratum fixed)."""
    v = np.asarray(vectors_enu, float)
    return _with_altitude(v, true_from_apparent_altitude(altitude_of(v), temperature_c, pressure_kpa))
