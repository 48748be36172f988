"""Resident space objects (satellites) and bright bodies near the field (Sease 2013 §"Resident Space
Object Implementation", eqs. 2.15-2.19; Jacobs 1995 §7.6; Sease 2013 Eq. 2.13–2.19).

An :class:`OrbitalScene` holds the observer's orbit (the spacecraft carrying the camera), the
objects' orbits and an exclusion angle. For one instant it gives a :class:`Snapshot`: positions and
velocities of everything, the Sun and the Moon. From a snapshot:

- an object's **line of sight** at times near the instant, from a second-order Taylor expansion of
  both orbits (position error < 1 mm over a second) with the light time taken into account;
- its **illumination**: outside the Earth's cylindrical shadow (eq. 2.15, applied to the object);
- its **magnitude**: a fixed V (as in the seed: Mv 1 or 4), or that of a Lambertian sphere of
  radius R and albedo rho at range d and solar phase angle phi::

      m = m_sun - 2.5 log10( 2/3 rho (R / d)^2 ((pi - phi) cos phi + sin phi) / pi ),
      m_sun = -26.74 (V)

- the **bright-body flags**: the angle from the boresight to the Sun, the Moon (seen from the
  observer) and the nearest point of the Earth's limb; a body is *in the field* when it comes
  within the half-diagonal field of view (the seed's ``asin(R / r) + FoV / 2`` test, eqs. 2.16-2.19,
  with the boresight the camera +z axis: the seed's erratum) and *near* when it comes within
  ``exclusion_deg`` of the boresight (28.1 deg: Jacobs 1995's baffle, §7.6).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from astropy.time import Time
from numpy.typing import ArrayLike, NDArray

from ..camera import Camera
from ..errors import InvalidInputError
from . import _checks
from ._orbits import R_EARTH_KM, R_MOON_KM, R_SUN_KM, Orbit, acceleration, in_earth_shadow, sun_moon_km

SUN_V_MAG: float = -26.74
LIGHT_KM_S: float = 299_792.458
DEFAULT_EXCLUSION_DEG: float = 28.1
"""Jacobs 1995 §7.6: direct light reaches the lens within 28.1 deg of the boresight."""


@dataclass(frozen=True)
class RSO:
    """A satellite to render: its orbit, and a fixed magnitude or a Lambertian sphere.

    Parameters
    ----------
    orbit : Orbit
    ident : int
        Identifier in the truth (e.g. a NORAD number).
    mag : float or None
        Fixed V magnitude when lit; None: the Lambertian sphere below.
    radius_m, albedo : float
        Sphere radius (m) and Bond albedo in (0, 1].
    """

    orbit: Orbit
    ident: int = 1
    mag: float | None = None
    radius_m: float = 1.0
    albedo: float = 0.2

    def __post_init__(self) -> None:
        if not isinstance(self.orbit, Orbit):
            raise InvalidInputError(f"orbit must be an Orbit, got {type(self.orbit).__name__}")
        _checks.positive("radius_m", self.radius_m)
        _checks.fraction("albedo", self.albedo)
        if self.mag is not None and not math.isfinite(self.mag):
            raise InvalidInputError(f"mag must be finite or None, got {self.mag!r}")


@dataclass(frozen=True)
class OrbitalScene:
    """The observer and the objects; the camera rides on ``observer``."""

    observer: Orbit
    rsos: tuple[RSO, ...] = ()
    exclusion_deg: float = DEFAULT_EXCLUSION_DEG

    def __post_init__(self) -> None:
        if not isinstance(self.observer, Orbit):
            raise InvalidInputError("observer must be an Orbit")
        object.__setattr__(self, "rsos", tuple(self.rsos))
        if not all(isinstance(r, RSO) for r in self.rsos):
            raise InvalidInputError("rsos must be RSO objects")
        _checks.positive("exclusion_deg", self.exclusion_deg)

    def snapshots(self, times: Time) -> list[Snapshot]:
        """The geometry at each of ``times`` (propagating every orbit once for all of them)."""
        times = Time(np.atleast_1d(times.jd1), np.atleast_1d(times.jd2), format="jd", scale=times.scale)
        obs_r, obs_v = self.observer.states_at(times)
        obj = [r.orbit.states_at(times) for r in self.rsos]
        sun, moon = sun_moon_km(times)
        return [Snapshot(time=times[k], observer_r=obs_r[k], observer_v=obs_v[k],
                         rso_r=np.array([o[0][k] for o in obj]).reshape(-1, 3),
                         rso_v=np.array([o[1][k] for o in obj]).reshape(-1, 3),
                         sun=sun[k], moon=moon[k], scene=self) for k in range(len(times))]


@dataclass(frozen=True, eq=False)
class Snapshot:
    """Positions (km) and velocities (km/s) at one instant ``time``, GCRS axes."""

    time: Time
    observer_r: NDArray[np.float64]
    observer_v: NDArray[np.float64]
    rso_r: NDArray[np.float64]
    rso_v: NDArray[np.float64]
    sun: NDArray[np.float64]
    moon: NDArray[np.float64]
    scene: OrbitalScene = field(repr=False)

    def lines_of_sight(self, dt_s: ArrayLike, index: NDArray[np.intp] | None = None) -> NDArray[np.float64]:
        """Unit directions (K, n, 3) from the observer to the objects ``index`` (all by default) at
        ``dt_s`` (K, n) seconds from the snapshot, as the light arriving then left the object
        (light time applied)."""
        index = np.arange(len(self.rso_r)) if index is None else np.asarray(index)
        r, v = self.rso_r[index], self.rso_v[index]
        dt = np.asarray(dt_s, dtype=float).reshape(len(r), -1)
        obs = _taylor(self.observer_r, self.observer_v, dt)
        tau = 0.0
        for _ in range(2):  # light-time iteration: the light left at dt - |los| / c
            los = _taylor(r[:, None, :], v[:, None, :], dt - tau) - obs
            tau = np.linalg.norm(los, axis=-1) / LIGHT_KM_S
        return los / np.linalg.norm(los, axis=-1, keepdims=True)

    def rso_ranges_km(self) -> NDArray[np.float64]:
        return np.linalg.norm(self.rso_r - self.observer_r, axis=-1)

    def rso_lit(self) -> NDArray[np.bool_]:
        """Objects outside the Earth's shadow (K,)."""
        return ~in_earth_shadow(self.rso_r, self.sun)

    def rso_magnitudes(self) -> NDArray[np.float64]:
        """V magnitude of each object (inf in the shadow)."""
        mags = np.array([_magnitude(rso, r, self.observer_r, self.sun)
                         for rso, r in zip(self.scene.rsos, self.rso_r, strict=True)]).reshape(-1)
        return np.where(self.rso_lit(), mags, np.inf)

    def bright_bodies(self, boresight_icrs: NDArray, camera: Camera) -> BrightBodyFlags:
        """Angles from the boresight to the Sun, Moon and Earth limb, and the flags."""
        half_fov = math.radians(camera.fov_diagonal_deg) / 2.0
        limit = math.radians(self.scene.exclusion_deg)
        angles = {}
        for name, centre, radius in (("sun", self.sun, R_SUN_KM), ("moon", self.moon, R_MOON_KM),
                                     ("earth", np.zeros(3), R_EARTH_KM)):
            rel = centre - self.observer_r
            dist = float(np.linalg.norm(rel))
            edge = _angle(boresight_icrs, rel) - math.asin(min(1.0, radius / dist))
            angles[name] = edge
        flags: dict[str, float | bool] = {f"{k}_edge_deg": math.degrees(v) for k, v in angles.items()}
        flags.update({f"{k}_in_fov": bool(v < half_fov) for k, v in angles.items()})
        flags.update({f"{k}_near": bool(v < limit) for k, v in angles.items()})
        return BrightBodyFlags(**flags)  # type: ignore[arg-type]  # (names and types as declared)


@dataclass(frozen=True, eq=False)
class LinesOfSight:
    """The objects of a snapshot as moving sources (:class:`.sampling.Directions`), on a clock
    whose time ``t_snapshot_s`` is the snapshot's instant."""

    snapshot: Snapshot
    t_snapshot_s: float
    index: NDArray[np.intp]

    def __len__(self) -> int:
        return int(self.index.size)

    def __call__(self, times: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.snapshot.lines_of_sight(np.asarray(times) - self.t_snapshot_s, self.index)

    def take(self, index: NDArray[np.intp]) -> LinesOfSight:
        return LinesOfSight(self.snapshot, self.t_snapshot_s, self.index[index])


@dataclass(frozen=True)
class BrightBodyFlags:
    """Angles (deg) from the boresight to the nearest edge of each body (negative: the boresight
    is on the body), whether the body is inside the field and whether it is near the boresight."""

    sun_edge_deg: float
    moon_edge_deg: float
    earth_edge_deg: float
    sun_in_fov: bool
    moon_in_fov: bool
    earth_in_fov: bool
    sun_near: bool
    moon_near: bool
    earth_near: bool

    @property
    def corrupted(self) -> bool:
        """True if the Sun or the Earth is in the field (Sease 2013: the frame is discarded)."""
        return self.sun_in_fov or self.earth_in_fov


def _taylor(r: NDArray, v: NDArray, dt: NDArray) -> NDArray:
    """Positions at ``dt`` (..., broadcast) from r, v and the two-body + J2 acceleration."""
    a = acceleration(r)
    dt = np.asarray(dt)[..., None]
    return r + v * dt + 0.5 * a * dt * dt


def _angle(u: NDArray, v: NDArray) -> float:
    return float(math.atan2(np.linalg.norm(np.cross(u, v)), float(np.dot(u, v))))


def _magnitude(rso: RSO, r: NDArray, observer: NDArray, sun: NDArray) -> float:
    if rso.mag is not None:
        return float(rso.mag)
    to_obs = observer - r
    to_sun = sun - r
    phase = _angle(to_obs, to_sun)
    d_m = float(np.linalg.norm(to_obs)) * 1e3
    sun_au = float(np.linalg.norm(to_sun)) / 149_597_870.7
    phase_fn = ((math.pi - phase) * math.cos(phase) + math.sin(phase)) / math.pi
    ratio = 2.0 / 3.0 * rso.albedo * (rso.radius_m / d_m) ** 2 * max(phase_fn, 1e-12) / sun_au**2
    return SUN_V_MAG - 2.5 * math.log10(ratio)
