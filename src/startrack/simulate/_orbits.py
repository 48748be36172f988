"""Orbits for the satellite scenes: Keplerian elements, two-body + J2 propagation, Earth shadow,
and the Sun and Moon (Sease 2013 §"Resident Space Object Implementation", eqs. 2.13-2.15;
Sease 2013 Eq. 2.13–2.19).

Frame: a geocentric inertial frame with the axes of GCRS, which are those of ICRS to within the
frame bias (23 mas) and aberration, so orbit positions and catalog directions are used in one
frame. Units: km, km/s, seconds. Dynamics (drag neglected, as in the seed)::

    r'' = -mu r / |r|^3 + a_J2,
    a_J2 = -3 J2 mu R^2 / (2 |r|^5) * [x (1 - 5 z^2/|r|^2), y (1 - 5 z^2/|r|^2), z (3 - 5 z^2/|r|^2)]

integrated with scipy's DOP853 (relative tolerance 1e-11). The Earth's shadow is the cylinder of
eq. 2.15 (Escobal), applied to the object's position (the seed's erratum). The Sun and Moon come
from astropy's built-in ephemeris (``get_body`` with ``"builtin"``: offline, arcminute-level),
computed in TDB so that no leap-second or Earth-orientation table is needed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from ..errors import InvalidInputError
from . import _checks

MU_EARTH_KM3_S2: float = 398_600.4418
R_EARTH_KM: float = 6378.137
J2_EARTH: float = 1.08263e-3
R_SUN_KM: float = 695_700.0
R_MOON_KM: float = 1737.4
_RTOL = 1e-11


@dataclass(frozen=True)
class KeplerElements:
    """Osculating Keplerian elements: a (km), e, and angles in radians (nu = true anomaly)."""

    a_km: float
    e: float
    i_rad: float
    raan_rad: float
    argp_rad: float
    nu_rad: float

    def __post_init__(self) -> None:
        _checks.positive("a_km", self.a_km)
        if not 0.0 <= self.e < 1.0:
            raise InvalidInputError(f"eccentricity e must be in [0, 1), got {self.e!r}")
        if self.a_km * (1.0 - self.e) <= R_EARTH_KM:
            raise InvalidInputError(f"perigee {self.a_km * (1 - self.e):.0f} km is inside the Earth")

    @classmethod
    def from_degrees(cls, a_km: float, e: float, i_deg: float, raan_deg: float, argp_deg: float,
                     nu_deg: float) -> KeplerElements:
        """Elements with the angles in degrees (as tables print them)."""
        return cls(a_km, e, *(math.radians(v) for v in (i_deg, raan_deg, argp_deg, nu_deg)))

    def state(self, mu_km3_s2: float = MU_EARTH_KM3_S2) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Position (km) and velocity (km/s) in the inertial frame."""
        p = self.a_km * (1.0 - self.e**2)
        r = p / (1.0 + self.e * math.cos(self.nu_rad))
        r_pf = r * np.array([math.cos(self.nu_rad), math.sin(self.nu_rad), 0.0])
        v_pf = math.sqrt(mu_km3_s2 / p) * np.array([-math.sin(self.nu_rad), self.e + math.cos(self.nu_rad), 0.0])
        rot = _perifocal_to_inertial(self.raan_rad, self.i_rad, self.argp_rad)
        return rot @ r_pf, rot @ v_pf

    @property
    def period_s(self) -> float:
        return 2.0 * math.pi * math.sqrt(self.a_km**3 / MU_EARTH_KM3_S2)


def _perifocal_to_inertial(raan: float, inc: float, argp: float) -> NDArray[np.float64]:
    def rz(a):
        c, s = math.cos(a), math.sin(a)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    c, s = math.cos(inc), math.sin(inc)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    return rz(raan) @ rx @ rz(argp)


def acceleration(r_km: NDArray, j2: bool = True) -> NDArray[np.float64]:
    """Two-body + J2 acceleration (km/s^2) at positions (..., 3) km (Sease 2013 eqs. 2.13-2.14)."""
    r = np.asarray(r_km, dtype=float)
    r2 = np.sum(r * r, axis=-1, keepdims=True)
    rn = np.sqrt(r2)
    acc = -MU_EARTH_KM3_S2 * r / (r2 * rn)
    if j2:
        z2 = r[..., 2:3] ** 2 / r2
        factor = -1.5 * J2_EARTH * MU_EARTH_KM3_S2 * R_EARTH_KM**2 / (r2 * r2 * rn)
        acc = acc + factor * r * np.concatenate([1 - 5 * z2, 1 - 5 * z2, 3 - 5 * z2], axis=-1)
    return acc


@dataclass(frozen=True, eq=False)
class Orbit:
    """A satellite's state at an epoch, propagated by two-body + J2 (``j2=False``: two-body).

    Parameters
    ----------
    epoch : astropy.time.Time
    r_km, v_km_s : array_like, shape (3,)
        Position and velocity at ``epoch`` (GCRS axes).
    j2 : bool
    """

    epoch: Time
    r_km: NDArray[np.float64]
    v_km_s: NDArray[np.float64]
    j2: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.epoch, Time) or not self.epoch.isscalar:
            raise InvalidInputError("epoch must be a single astropy Time")
        r = _checks.finite_array("r_km", self.r_km, (3,)).copy()
        v = _checks.finite_array("v_km_s", self.v_km_s, (3,)).copy()
        if np.linalg.norm(r) <= R_EARTH_KM:
            raise InvalidInputError("r_km must be outside the Earth (|r| > 6378 km)")
        object.__setattr__(self, "r_km", r)
        object.__setattr__(self, "v_km_s", v)

    @classmethod
    def from_elements(cls, epoch: Time, elements: KeplerElements, j2: bool = True) -> Orbit:
        return cls(epoch, *elements.state(), j2=j2)

    def states(self, dt_s: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Positions (N, 3) km and velocities (N, 3) km/s at ``dt_s`` (N,) seconds from the epoch."""
        dt = np.atleast_1d(np.asarray(dt_s, dtype=float))
        if dt.ndim != 1 or not np.all(np.isfinite(dt)):
            raise InvalidInputError("dt_s must be finite seconds, a number or a 1-D array")
        r, v = np.empty((dt.size, 3)), np.empty((dt.size, 3))
        y0 = np.concatenate([self.r_km, self.v_km_s])
        for sign in (1.0, -1.0):
            sel = np.flatnonzero(dt * sign > 0)
            if sel.size:  # solve_ivp needs strictly monotonic times: propagate each time once
                times, back = np.unique(dt[sel] * sign, return_inverse=True)
                sol = solve_ivp(self._rhs, (0.0, sign * float(times[-1])), y0, method="DOP853",
                                t_eval=sign * times, rtol=_RTOL, atol=1e-9)
                r[sel], v[sel] = sol.y[:3, back].T, sol.y[3:, back].T
        at_epoch = dt == 0
        r[at_epoch], v[at_epoch] = self.r_km, self.v_km_s
        return r, v

    def states_at(self, times: Time) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`states` at astropy times (any scale)."""
        return self.states(np.atleast_1d((times - self.epoch).to_value("s")))

    def _rhs(self, _t: float, y: NDArray) -> NDArray:
        return np.concatenate([y[3:], acceleration(y[:3], self.j2)])


def in_earth_shadow(r_km: ArrayLike, sun_km: ArrayLike) -> NDArray[np.bool_]:
    """True where positions (..., 3) lie in the Earth's cylindrical shadow (Sease 2013 eq. 2.15)."""
    r = np.asarray(r_km, dtype=float)
    s_hat = np.asarray(sun_km, dtype=float)
    s_hat = s_hat / np.linalg.norm(s_hat, axis=-1, keepdims=True)
    along = np.sum(r * s_hat, axis=-1)
    perpendicular = np.linalg.norm(r - along[..., None] * s_hat, axis=-1)
    return (along < 0) & (perpendicular < R_EARTH_KM)


def sun_moon_km(times: Time) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Geocentric Sun and Moon positions (N, 3) km, GCRS axes, from astropy's built-in ephemeris."""
    from astropy.coordinates import get_body, solar_system_ephemeris

    tdb = Time(np.atleast_1d(times.tdb.jd1), np.atleast_1d(times.tdb.jd2), format="jd", scale="tdb")
    with solar_system_ephemeris.set("builtin"):
        sun = get_body("sun", tdb).cartesian.xyz.to_value("km")
        moon = get_body("moon", tdb).cartesian.xyz.to_value("km")
    return np.asarray(sun).T.reshape(-1, 3), np.asarray(moon).T.reshape(-1, 3)
