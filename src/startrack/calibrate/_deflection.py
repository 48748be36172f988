"""Light deflection by the giant planets, where it matters (IERS Conventions 2010 §5.5.8).

A body of mass M deflects starlight passing at angle theta from it, seen from distance d, by
``4 G M / (c^2 d theta)`` (small theta; :func:`deflection_near_planet_rad`), at the limb
:func:`limb_deflection_rad`. The Sun gives 1.75 arcsec at its limb and still 4 mas at 90 deg (always
applied, :mod:`._apparent`). Jupiter (4.0-6.4 au away) gives **16.3 mas** at its limb, 4-7 mas
1 arcmin from its centre, 0.4-0.7 mas at 10 arcmin and 0.07-0.11 mas at 1 deg; Saturn (8-11 au)
**5.8 mas** at its limb, 0.7-1.0 mas at 1 arcmin and < 0.02 mas at 1 deg. A star tracker
(arcsecond pixels) never sees either; they matter for milliarcsecond astrometry of stars within
arcminutes of a planet, so they are optional (``apparent_vectors(..., planets=True)``).

The deflection is ERFA's ``ldn`` (Klioner 2003): each planet placed back along its barycentric
track by the light time to the observer, ERFA's masses and deflection limiters (its note 4).
Barycentric positions come from astropy's built-in ephemeris (``erfa.plan94`` + ``epv00``:
arcseconds for Jupiter and Saturn, ample for a 16 mas effect), offline. astropy's own GCRS applies
the Sun only, so this is checked against the formula above, not against astropy.
"""

from __future__ import annotations

import warnings

import astropy.units as u
import erfa
import numpy as np
from astropy.coordinates import get_body_barycentric_posvel
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ..frames import normalize

PLANETS: dict[str, tuple[float, float]] = {"jupiter": (0.00095435, 3e-9), "saturn": (0.00028574, 3e-10)}
"""Mass (solar masses) and ERFA deflection limiter (phi^2 / 2) of each planet (ERFA ``ldn`` note 4)."""
EQUATORIAL_RADIUS_M: dict[str, float] = {"sun": 6.957e8, "jupiter": 7.1492e7, "saturn": 6.0268e7}
"""IAU 2015 nominal equatorial radii (Sun: IAU 2015 B3; planets: IAU WGCCRE 2015), m."""
_MASS_SOLAR = {"sun": 1.0, **{name: mass for name, (mass, _) in PLANETS.items()}}
_SRS_M = 2953.25008  # 2 G M_sun / c^2, m (ERFA's SRS x au)


def limb_deflection_rad(name: str) -> float:
    """Deflection of a ray grazing the body's equator, ``2 SRS M / R`` (radians)."""
    key = _body_name(name, ("sun", *PLANETS))
    return 2.0 * _SRS_M * _MASS_SOLAR[key] / EQUATORIAL_RADIUS_M[key]


def planet_table(time: Time, names: tuple[str, ...] = tuple(PLANETS)) -> NDArray:
    """ERFA ``eraLDBODY`` records (mass, limiter, barycentric position au / velocity au/day) at ``time``."""
    keys = [_body_name(n, tuple(PLANETS)) for n in names]
    table = np.zeros(len(keys), dtype=erfa.dt_eraLDBODY)
    t = time.tdb
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=erfa.ErfaWarning)
        for i, key in enumerate(keys):
            pos, vel = get_body_barycentric_posvel(key, t, ephemeris="builtin")
            table[i] = (*PLANETS[key], (pos.xyz.to_value(u.au), vel.xyz.to_value(u.au / u.day)))
    return table


def deflect_by_planets(vectors: ArrayLike, observer_au: ArrayLike, time: Time,
                       names: tuple[str, ...] = tuple(PLANETS)) -> NDArray[np.float64]:
    """Light deflection of star directions (N, 3) by the planets ``names`` (not the Sun).

    Parameters
    ----------
    vectors : array_like, shape (N, 3)
        Unit directions observer -> star, ICRS axes (after parallax, before aberration).
    observer_au : array_like, shape (3,)
        Barycentric position of the observer, au (``ObserverState.position_au``).
    time : astropy.time.Time
        Scalar time of observation.
    """
    p = np.asarray(vectors, dtype=float)
    ob = np.asarray(observer_au, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or ob.shape != (3,):
        raise InvalidInputError(f"vectors must be (N, 3) and observer_au (3,), got {p.shape} and {ob.shape}")
    if not names:
        return p.copy()
    return normalize(erfa.ldn(planet_table(time, names), ob, p))


def _body_name(name: str, valid: tuple[str, ...]) -> str:
    key = str(name).lower()
    if key not in valid:
        raise InvalidInputError(f"body must be one of {valid}, got {name!r}")
    return key


def deflection_near_planet_rad(name: str, distance_m: float, separation_rad: ArrayLike) -> NDArray[np.float64]:
    """Small-angle deflection ``2 SRS M / (d theta)`` of a star ``separation_rad`` from the planet's
    centre seen from ``distance_m`` (the size of the effect, for documentation and checks)."""
    key = _body_name(name, ("sun", *PLANETS))
    theta = np.asarray(separation_rad, dtype=float)
    return 2.0 * _SRS_M * _MASS_SOLAR[key] / (float(distance_m) * theta) * np.ones_like(theta)

