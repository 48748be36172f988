"""Sun, Earth-limb and Moon exclusion of each head of a rig.

A head is blinded when a bright body's nearest edge comes within its exclusion angle of its
boresight (:class:`startrack.rig.Exclusion`, one set of angles per head, as its baffle allows):
the edge angle is the angle from the boresight to the body's centre minus the body's angular
radius ``asin(R / d)`` (the test of Sease 2013 eqs. 2.16-2.19, :meth:`startrack.simulate._rso.Snapshot.bright_bodies`).
The directions come from an observer position and a time (the Sun and the Moon from astropy's
built-in ephemeris, :func:`startrack.simulate._orbits.sun_moon_km`), or from a simulator snapshot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ..frames import angle_between
from ..rig import RigHead
from ..simulate import R_EARTH_KM, R_MOON_KM, R_SUN_KM, sun_moon_km

BODIES = ("sun", "earth", "moon")
"""The bodies tested, in the order a blinded head names the first that blinds it."""


@dataclass(frozen=True)
class BrightBodies:
    """Directions from the observer (ICRS / GCRS unit vectors, shape (3,)) to the Sun, the Earth's
    centre and the Moon, and their angular radii (rad)."""

    sun_icrs: NDArray[np.float64]
    earth_icrs: NDArray[np.float64]
    moon_icrs: NDArray[np.float64]
    sun_radius_rad: float
    earth_radius_rad: float
    moon_radius_rad: float

    @classmethod
    def at(cls, time: Time, observer_km: ArrayLike) -> BrightBodies:
        """The bodies seen from a geocentric position (km, GCRS axes) at a time."""
        observer = np.asarray(observer_km, dtype=float)
        if observer.shape != (3,) or not np.linalg.norm(observer) > R_EARTH_KM:
            raise InvalidInputError(f"observer_km must be a position (3,) above the Earth's surface, "
                                    f"got {observer_km!r}")
        sun, moon = (v[0] for v in sun_moon_km(time))
        return cls.from_positions(observer, sun, moon)

    @classmethod
    def from_positions(cls, observer_km: NDArray, sun_km: NDArray, moon_km: NDArray) -> BrightBodies:
        """From geocentric positions (km) of the observer, the Sun and the Moon."""
        parts = {}
        for name, centre, radius in (("sun", sun_km, R_SUN_KM), ("earth", np.zeros(3), R_EARTH_KM),
                                     ("moon", moon_km, R_MOON_KM)):
            rel = np.asarray(centre, dtype=float) - observer_km
            dist = float(np.linalg.norm(rel))
            parts[f"{name}_icrs"] = rel / dist
            parts[f"{name}_radius_rad"] = math.asin(min(1.0, radius / dist))
        return cls(**parts)

    @classmethod
    def dawn_dusk(cls, time: Time, altitude_km: float = 500.0) -> BrightBodies:
        """An observer at ``altitude_km`` above the point 90 deg from the Sun (on the terminator,
        towards the celestial north of it): the dawn-dusk orbit of many Earth-observing missions."""
        sun, _ = sun_moon_km(time)
        s = sun[0] / np.linalg.norm(sun[0])
        side = np.cross(s, [0.0, 0.0, 1.0])
        side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-9 else np.array([1.0, 0.0, 0.0])
        return cls.at(time, (R_EARTH_KM + float(altitude_km)) * np.cross(side, s))

    @classmethod
    def from_snapshot(cls, snapshot) -> BrightBodies:
        """From a :class:`startrack.simulate._rso.Snapshot`."""
        return cls.from_positions(np.asarray(snapshot.observer_r, dtype=float), snapshot.sun, snapshot.moon)


def dawn_dusk_bodies(time_utc: str | Time, altitude_km: float = 500.0) -> BrightBodies:
    """:meth:`BrightBodies.dawn_dusk` from an ISO UTC time (text, as the command line gives it)."""
    if isinstance(time_utc, Time):
        time = time_utc
    else:
        try:
            time = Time(time_utc, scale="utc")
        except ValueError:
            raise InvalidInputError(f"time {time_utc!r} is not an ISO time such as 2025-03-20T12:00:00") from None
    altitude = float(altitude_km)
    if not (math.isfinite(altitude) and altitude > 0):
        raise InvalidInputError(f"the orbit altitude must be a positive number of km, got {altitude_km!r}")
    return BrightBodies.dawn_dusk(time, altitude)


def edge_angles_rad(bodies: BrightBodies, boresights_icrs: ArrayLike) -> dict[str, NDArray[np.float64]]:
    """Angle (rad) from each boresight (..., 3) to the nearest edge of each body (negative: on it)."""
    b = np.asarray(boresights_icrs, dtype=float)
    return {name: angle_between(b, getattr(bodies, f"{name}_icrs")) - getattr(bodies, f"{name}_radius_rad")
            for name in BODIES}


def limits_rad(head: RigHead) -> dict[str, float]:
    """The head's exclusion half-angles by body (rad)."""
    ex = head.exclusion
    return {"sun": math.radians(ex.sun_deg), "earth": math.radians(ex.earth_limb_deg),
            "moon": math.radians(ex.moon_deg)}


def blinded_mask(head: RigHead, bodies: BrightBodies, boresights_icrs: ArrayLike) -> NDArray[np.bool_]:
    """Whether the head is blinded at each of its boresights (..., 3) (ICRS)."""
    edges, limits = edge_angles_rad(bodies, boresights_icrs), limits_rad(head)
    return np.logical_or.reduce([edges[n] < limits[n] for n in BODIES])


def blinded_by(head: RigHead, bodies: BrightBodies | None, boresight_icrs: ArrayLike) -> str:
    """The first body (of :data:`BODIES`) that blinds the head at this boresight, or "" (none, or no bodies)."""
    if bodies is None:
        return ""
    edges, limits = edge_angles_rad(bodies, boresight_icrs), limits_rad(head)
    return next((n for n in BODIES if float(edges[n]) < limits[n]), "")
