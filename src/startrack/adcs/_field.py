"""Magnetic fields in the reference frame: the uniform field of a Helmholtz test bed and an
axial centred dipole seen along a circular orbit.

The dipole (Wertz, *Spacecraft Attitude Determination and Control*, 1978, §5.1 and App. H):
``B(r) = mu0 m / (4 pi |r|^3) (3 (m_hat . r_hat) r_hat - m_hat)`` with Earth's moment
m = 7.94e22 A m^2 pointing to geographic south (``m_hat = -z``), about 30 uT at the equator's
surface and twice that at the poles. The dipole is on the spin axis, so the field in the inertial
frame does not depend on Earth's rotation; the reference frame is then inertial (ICRS-aligned
axes) and the orbit circular, starting at its ascending node at t = 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError

EARTH_RADIUS_M = 6.371e6
EARTH_GM_M3_S2 = 3.986004418e14
EARTH_DIPOLE_A_M2 = 7.94e22


class FieldModel(Protocol):
    """The magnetic field (T) in the reference frame at times ``t_s``: shape (..., 3)."""

    def field_ref(self, t_s: ArrayLike) -> NDArray[np.float64]: ...


@dataclass(frozen=True)
class UniformField:
    """A constant field (a Helmholtz coil): ``b_ref_t`` (3,), T, in the reference frame."""

    b_ref_t: tuple[float, float, float]

    def __post_init__(self) -> None:
        b = np.asarray(self.b_ref_t, dtype=float)
        if b.shape != (3,) or not np.all(np.isfinite(b)) or not np.any(b):
            raise InvalidInputError(f"b_ref_t must be 3 finite numbers (T), not all zero, got {self.b_ref_t!r}")
        object.__setattr__(self, "b_ref_t", tuple(b.tolist()))

    def field_ref(self, t_s: ArrayLike) -> NDArray[np.float64]:
        t = np.asarray(t_s, dtype=float)
        return np.broadcast_to(np.asarray(self.b_ref_t), t.shape + (3,)).copy()


def dipole_field_t(position_m: ArrayLike, moment_a_m2: float = EARTH_DIPOLE_A_M2) -> NDArray[np.float64]:
    """Field of the axial centred dipole (moment along -z) at positions (..., 3) in m, T."""
    r = np.asarray(position_m, dtype=float)
    dist = np.linalg.norm(r, axis=-1, keepdims=True)
    if np.any(dist <= 0):
        raise InvalidInputError("position_m must not be the dipole's centre")
    r_hat = r / dist
    m_hat = np.array([0.0, 0.0, -1.0])
    scale = 1e-7 * moment_a_m2 / dist**3
    return scale * (3.0 * (r_hat @ m_hat)[..., None] * r_hat - m_hat)


@dataclass(frozen=True)
class DipoleField:
    """The dipole field along a circular orbit of ``altitude_km`` and ``inclination_deg``."""

    altitude_km: float = 500.0
    inclination_deg: float = 51.6

    def __post_init__(self) -> None:
        if not (math.isfinite(self.altitude_km) and self.altitude_km > 0):
            raise InvalidInputError(f"altitude_km must be positive, got {self.altitude_km!r}")
        if not (math.isfinite(self.inclination_deg) and 0 <= self.inclination_deg <= 180):
            raise InvalidInputError(f"inclination_deg must be in [0, 180], got {self.inclination_deg!r}")

    @property
    def radius_m(self) -> float:
        return EARTH_RADIUS_M + 1e3 * self.altitude_km

    @property
    def period_s(self) -> float:
        return 2.0 * math.pi * math.sqrt(self.radius_m**3 / EARTH_GM_M3_S2)

    def position_m(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """Orbit positions (..., 3), m, in the reference (inertial) frame."""
        u = 2.0 * math.pi * np.asarray(t_s, dtype=float) / self.period_s  # argument of latitude
        inc = math.radians(self.inclination_deg)
        return self.radius_m * np.stack([np.cos(u), np.sin(u) * math.cos(inc), np.sin(u) * math.sin(inc)], axis=-1)

    def field_ref(self, t_s: ArrayLike) -> NDArray[np.float64]:
        return dipole_field_t(self.position_m(t_s))
