"""Spectral response of a sensor and the colour term it gives a star of known ``B - V``.

Magnitudes in the catalog are Johnson V, and the zero point of :mod:`._radiometry` counts the
photons of a V = 0 star over the V passband (a top hat of 88 nm at 550 nm, the width that makes
``F_nu / h * d_lambda / lambda`` the photon flux). A sensor whose band differs from V (an
unfiltered silicon detector, a red filter) collects a different number of photons from two stars
of the same V but different colour. We model each star as a blackbody of the temperature that
its ``B - V`` implies (Ballesteros 2012, EPL 97, 34008, eq. 14)::

    T = 4600 K * (1 / (0.92 (B-V) + 1.7) + 1 / (0.92 (B-V) + 0.62))

and scale the V-band photons by the ratio of the blackbody's photons weighted by the sensor's
relative response ``R(lambda)`` (peak 1) to its photons in the V top hat::

    colour_factor(B-V) = integral N_lambda(T) R(lambda) d lambda
                         / integral_{506 nm}^{594 nm} N_lambda(T) d lambda

For the V top hat itself the factor is exactly 1 for every colour. The blackbody is crude in the
ultraviolet of hot stars and the molecular bands of M stars (errors of 10-20 % in the factor);
it is the colour *dependence* that matters here (Huffman 2006 §5.3: "spectral response differs
between imagers"), and the factor is tabulated once per passband on a grid of ``B - V``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError

PLANCK_J_S = 6.62607015e-34
LIGHT_M_S = 299_792_458.0
BOLTZMANN_J_K = 1.380649e-23
V_TOP_HAT_NM: tuple[float, float] = (506.0, 594.0)
"""The V band as a top hat of 88 nm centred on 550 nm (the band of the radiometric zero point)."""
DEFAULT_B_V: float = 0.6
"""Colour assumed for a star without a catalog ``B - V`` (about the median of stars to V 7)."""
SUN_B_V: float = 0.65
"""Colour of sunlight (zodiacal light and sunlit satellites)."""
_BV_GRID = np.linspace(-0.4, 2.2, 131)


def temperature_from_b_v(b_v: ArrayLike) -> NDArray[np.float64]:
    """Blackbody temperature (K) of a star of colour ``b_v`` (Ballesteros 2012, eq. 14)."""
    bv = np.asarray(b_v, dtype=float)
    return 4600.0 * (1.0 / (0.92 * bv + 1.7) + 1.0 / (0.92 * bv + 0.62))


def photon_radiance(wavelength_nm: ArrayLike, temperature_k: ArrayLike) -> NDArray[np.float64]:
    """Blackbody photon spectral radiance, photons s^-1 m^-2 sr^-1 m^-1 (any common scale works)."""
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    t = np.asarray(temperature_k, dtype=float)
    x = PLANCK_J_S * LIGHT_M_S / (lam * BOLTZMANN_J_K * t)
    return 2.0 * LIGHT_M_S / lam**4 / np.expm1(x)


@dataclass(frozen=True)
class Passband:
    """Relative spectral response of optics + detector (peak 1), photon-counting.

    Parameters
    ----------
    name : str
    wavelength_nm : tuple of float
        Increasing wavelengths, nm.
    response : tuple of float
        Relative electrons per photon at each wavelength, in [0, 1]; linear in between, 0 outside.
        The absolute scale is ``Detector.quantum_efficiency * Optics.transmission``.
    """

    name: str
    wavelength_nm: tuple[float, ...]
    response: tuple[float, ...]

    def __post_init__(self) -> None:
        lam = np.asarray(self.wavelength_nm, dtype=float)
        resp = np.asarray(self.response, dtype=float)
        if lam.ndim != 1 or lam.shape != resp.shape or lam.size < 2:
            raise InvalidInputError("passband wavelength_nm and response must be two equal-length "
                                    "sequences of at least 2 numbers")
        if not (np.all(np.isfinite(lam)) and np.all(np.diff(lam) > 0) and lam[0] > 0):
            raise InvalidInputError("passband wavelength_nm must be positive and increasing")
        if not (np.all(np.isfinite(resp)) and resp.min() >= 0 and resp.max() <= 1 and resp.max() > 0):
            raise InvalidInputError("passband response must lie in [0, 1] with a positive peak")
        object.__setattr__(self, "wavelength_nm", tuple(float(v) for v in lam))
        object.__setattr__(self, "response", tuple(float(v) for v in resp))

    def colour_factor(self, b_v: ArrayLike) -> NDArray[np.float64]:
        """Sensor-band photons per V-band photon of stars of colour ``b_v`` (NaN -> DEFAULT_B_V).

        Linear interpolation in a table over B - V = -0.4 .. 2.2 (held constant beyond).
        """
        bv = np.asarray(b_v, dtype=float)
        bv = np.where(np.isnan(bv), DEFAULT_B_V, bv)
        return np.interp(bv, _BV_GRID, _factor_table(self))


@functools.lru_cache(maxsize=16)
def _factor_table(band: Passband) -> NDArray[np.float64]:
    """colour_factor on _BV_GRID, by trapezoidal integration on a 1 nm grid."""
    lo = min(band.wavelength_nm[0], V_TOP_HAT_NM[0])
    hi = max(band.wavelength_nm[-1], V_TOP_HAT_NM[1])
    lam = np.arange(math.floor(lo), math.ceil(hi) + 1.0, 1.0)
    resp = np.interp(lam, band.wavelength_nm, band.response, left=0.0, right=0.0)
    v_band = ((lam >= V_TOP_HAT_NM[0]) & (lam <= V_TOP_HAT_NM[1])).astype(float)
    n = photon_radiance(lam[None, :], temperature_from_b_v(_BV_GRID)[:, None])
    table = np.trapezoid(n * resp, lam, axis=1) / np.trapezoid(n * v_band, lam, axis=1)
    table.flags.writeable = False
    return table


V_BAND = Passband("johnson-v-top-hat", (V_TOP_HAT_NM[0] - 1e-6, *V_TOP_HAT_NM, V_TOP_HAT_NM[1] + 1e-6),
                  (0.0, 1.0, 1.0, 0.0))
"""The V top hat: colour factor 1 for every star (the default band of every sensor)."""

SILICON_UNFILTERED = Passband(
    "silicon-unfiltered",
    (350.0, 400.0, 450.0, 500.0, 550.0, 600.0, 650.0, 700.0, 750.0, 800.0, 850.0, 900.0, 950.0,
     1000.0, 1050.0),
    (0.20, 0.45, 0.70, 0.90, 1.00, 0.95, 0.85, 0.72, 0.58, 0.45, 0.33, 0.22, 0.12, 0.05, 0.0))
"""[ours] The shape of a generic front-illuminated CMOS quantum-efficiency curve with no filter
(peak at 550 nm); about 4-5 times the V-band photons of a solar-type star, more for red stars."""

PASSBANDS: dict[str, Passband] = {"v": V_BAND, "silicon": SILICON_UNFILTERED}
