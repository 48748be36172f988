"""The KnightCube of Sease 2013 ch. 5 (Sease 2013 Chapter 5): inertia, torque coil
and the Helmholtz field of its test bed, as one frozen set of parameters.

From the seed: J = diag(1.10, 1.05, 0.99) 1e-2 kg m^2 (Table 5.1), coils of 80 turns and 15-25
ohm on 3.4 V with |I| <= 0.148 A for the active coil (p. 65-66), a Helmholtz field of about
4.5 G (eq. 5.34: 9.98 G measured at 2.19 A, so about 0.99 A for 4.5 G).

Ours, because the seed does not give them:

* the coil's effective area per turn, 0.0064 m^2 (an 8 cm x 8 cm loop on a 10 cm face);
* the resistance, 23 ohm = 3.4 V / 0.148 A (inside the seed's 15-25 ohm, and the value that makes
  its current limit the H-bridge's full duty cycle);
* the default inertia: the seed's printed J is about ten times that of a uniform 611 g, 10 cm
  cube (m a^2 / 6 = 1.02e-3 kg m^2; possibly a typo). With it, 80 turns x
  0.0064 m^2 x 4.5 G x 0.148 A give 3.3e-3 rad/s^2, and a +0.1 step in q2 (about 0.2 rad) takes
  at least 16 s even bang-bang, which cannot meet the seed's own rise time (< 8 s, Table 5.3) or
  its 10 s plans. We take J scaled by 0.1 (J22 = 1.05e-3 kg m^2) by default; ``seed_printed()``
  gives the printed values.

Frames: the body frame is the cube's; the reference (lab or inertial) frame is fixed. The
single-axis motion is a rotation by theta about the shared y axis, ``q2 = sin(theta / 2)``; the
active coil's normal is body +z and the Helmholtz field points along reference +x, so the coil
torque about y is ``n A |B| I cos(theta) = n A |B| I (1 - 2 q2^2)`` (seed eq. 5.4-5.6).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError

GAUSS_T = 1e-4
"""One gauss in tesla."""
MU0_T_M_A = 4e-7 * math.pi
"""Vacuum permeability, T m / A."""
SEED_INERTIA_KG_M2 = (1.10e-2, 1.05e-2, 0.99e-2)
"""Sease 2013 Table 5.1, as printed (diagonal, kg m^2)."""


def helmholtz_field_t(turns: int, current_a: float, radius_m: float) -> float:
    """Field at the centre of a Helmholtz pair, ``(4/5)^(3/2) mu0 n I / R`` (seed eq. 5.34), T."""
    return (0.8 ** 1.5) * MU0_T_M_A * turns * current_a / radius_m


def _scaled(values: tuple[float, float, float], factor: float) -> tuple[float, float, float]:
    """Three values times ``factor``."""
    a, b, c = values
    return a * factor, b * factor, c * factor


@dataclass(frozen=True)
class CubeSat:
    """Inertia and magnetic torque coils of the satellite, and the field strength it sits in.

    Parameters
    ----------
    inertia_kg_m2 : tuple of 3 floats
        Principal moments (J11, J22, J33), kg m^2. Single-axis motion uses J22.
    turns : int
        Turns of each coil.
    coil_area_m2 : float
        Effective area of one turn, m^2.
    resistance_ohm : float
        Coil resistance (power = I^2 R), ohm.
    max_current_a : float
        Current limit of each coil, A.
    field_t : float
        Field strength |B| of the test bed (the Helmholtz coil), T.
    current_noise_a : float
        Half-width of the uniform actuation error added to each delivered current
        (seed: |dI| = 3.5e-3 A, the PWM resolution), A.
    """

    inertia_kg_m2: tuple[float, float, float] = field(
        default_factory=lambda: _scaled(SEED_INERTIA_KG_M2, 0.1))
    turns: int = 80
    coil_area_m2: float = 0.0064
    resistance_ohm: float = 23.0
    max_current_a: float = 0.148
    field_t: float = 4.5 * GAUSS_T
    current_noise_a: float = 3.5e-3

    def __post_init__(self) -> None:
        inertia = tuple(float(j) for j in np.asarray(self.inertia_kg_m2, dtype=float).ravel())
        if len(inertia) != 3 or not all(math.isfinite(j) and j > 0 for j in inertia):
            raise InvalidInputError(f"inertia_kg_m2 must be 3 positive moments (kg m^2), got {self.inertia_kg_m2!r}")
        object.__setattr__(self, "inertia_kg_m2", inertia)
        if not (isinstance(self.turns, int | np.integer) and self.turns >= 1):
            raise InvalidInputError(f"turns must be a whole number >= 1, got {self.turns!r}")
        for name in ("coil_area_m2", "resistance_ohm", "max_current_a", "field_t"):
            _positive(name, getattr(self, name))
        if not (math.isfinite(self.current_noise_a) and self.current_noise_a >= 0):
            raise InvalidInputError(f"current_noise_a must be >= 0 A, got {self.current_noise_a!r}")

    @classmethod
    def seed_printed(cls, **kwargs) -> CubeSat:
        """The seed's Table 5.1 inertia as printed (J22 = 1.05e-2 kg m^2)."""
        return cls(inertia_kg_m2=SEED_INERTIA_KG_M2, **kwargs)

    def with_j22(self, j22_kg_m2: float) -> CubeSat:
        """The same satellite with another J22 (the other moments scaled alike)."""
        scale = _positive("j22_kg_m2", j22_kg_m2) / self.j22
        return replace(self, inertia_kg_m2=_scaled(self.inertia_kg_m2, scale))

    @property
    def j22(self) -> float:
        """Moment of inertia about the rotation axis y, kg m^2."""
        return self.inertia_kg_m2[1]

    @property
    def inertia_matrix(self) -> NDArray[np.float64]:
        return np.diag(self.inertia_kg_m2)

    @property
    def moment_per_amp(self) -> float:
        """Magnetic moment of one coil per ampere, n A (A m^2 / A)."""
        return self.turns * self.coil_area_m2

    @property
    def max_accel_rad_s2(self) -> float:
        """Largest angular acceleration about y (coil normal across the field), rad/s^2."""
        return self.moment_per_amp * self.field_t * self.max_current_a / self.j22


def _positive(name: str, value: float) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = float("nan")
    if not (math.isfinite(number) and number > 0):
        raise InvalidInputError(f"{name} must be a positive finite number, got {value!r}")
    return number
