"""Radiometry: from a star's visual magnitude to the electrons it frees in the detector.

The signal model is Huffman 2006 §3.1 eq. 3.4 with its ad-hoc zero point
"28" replaced by a physical photon flux (errata in Huffman 2006)::

    electrons = PHI_0 * 10**(-0.4 * m_V) * aperture_area * transmission * QE * exposure

``PHI_0`` is the photon flux of a V = 0 star over the Johnson V passband, derived here from the
V-band zero point of Bessell, Castelli & Plez (1998, A&A 333, 231, Table A2): F_nu = 3636 Jy at
lambda_eff ~ 550 nm. Counting photons over a passband of width 88 nm::

    PHI_0 = F_nu / h * (delta_lambda / lambda) = 3.636e-23 / 6.626e-34 * 88 / 550
          = 8.78e9 photons s^-1 m^-2

This agrees with the textbook rule of about 1000 photons s^-1 cm^-2 A^-1 at V for a
magnitude-0 star (8.8e9 over 88 nm) and with the "about 1e10 photons s^-1 m^-2" that Sease 2013 implies
(Sease 2013 Eq. 2.7–2.8). It counts only V-band photons: an unfiltered silicon sensor collects
several times more from the same star, which a caller models with ``zero_point_photons_s_m2`` or
an effective QE, or gives the sensor a :class:`.passband.Passband`: then each star's V-band
photons are scaled by the colour factor of its ``B - V`` (a blackbody ratio, see
:mod:`._passband`).

Settings are frozen dataclasses: :class:`Optics` (aperture, transmission, PSF width),
:class:`Detector` (QE, gain, read noise, dark current, bias, full well, ADC bits) and
:class:`Sensor` (optics + detector + exposure time). :data:`SENSOR_PRESETS` holds the Huffman 2006
Table 7.1 FAR-MST sensor, which pairs with the ``"far-mst"`` camera preset, and a
variant with the seed's literal eq. 3.4 signal scale for reproducing its tables.

With the physical V-band zero point the FAR-MST sensor is faint: a V = 2 star gives 6.7e3 e-, a
peak pixel of 167 e- against 39.5 e- of read + dark noise (peak SNR 4.2), so few stars per frame
pass a 5-sigma threshold. That is what V-band photons through a 1.5 cm aperture in 0.1 s give;
an unfiltered sensor sees more (raise ``zero_point_photons_s_m2`` to model its band).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import preset_key
from ..errors import InvalidInputError
from . import _checks
from ._passband import Passband

PLANCK_J_S: float = 6.62607015e-34
V_BAND_ZERO_POINT_JY: float = 3636.0
"""Flux density of a V = 0 star, Bessell, Castelli & Plez (1998) Table A2."""
V_BAND_CENTER_NM: float = 550.0
V_BAND_WIDTH_NM: float = 88.0
JANSKY_W_M2_HZ: float = 1e-26

V_MAG0_PHOTONS_S_M2: float = (
    V_BAND_ZERO_POINT_JY * JANSKY_W_M2_HZ / PLANCK_J_S * V_BAND_WIDTH_NM / V_BAND_CENTER_NM
)
"""Photons s^-1 m^-2 from a V = 0 star over the V passband (8.78e9; see the module docstring)."""

@dataclass(frozen=True)
class Optics:
    """The lens: collecting area, throughput and point-spread width.

    Parameters
    ----------
    aperture_area_m2 : float
        Clear aperture area in m^2 (see :meth:`from_diameter`).
    transmission : float
        Fraction of the light entering the aperture that reaches the detector, in (0, 1].
    psf_sigma_px : float
        Standard deviation of the Gaussian PSF per axis, in pixels (Huffman 2006 §3.1 eq. 3.3;
        sigma = psfWidth / 4).
    zero_point_photons_s_m2 : float
        Photon flux of a magnitude-0 star in the band the detector sees, photons s^-1 m^-2.
    psf : {"gaussian", "airy"}
        PSF shape (see :mod:`._optics`): the pixel-integrated Gaussian of Huffman 2006, or the Airy
        pattern of a diffraction-limited circular aperture.
    airy_first_zero_px : float or None
        Radius of the Airy pattern's first dark ring (1.22 lambda N / pitch), px; None takes the
        Airy pattern whose best-fit Gaussian has ``psf_sigma_px`` (r0 = sigma / 0.3443).
    field_curvature : float
        PSF growth at the image corner: sigma(r) = sigma (1 + field_curvature (r / r_corner)^2)
        (Huffman 2006 §2.3: a single lens's field curvature), >= 0.
    natural_vignetting : bool
        Apply the cos^4 law: stars dim by cos(theta) (projected aperture), the sky background
        per pixel by cos^4(theta) (Fowler 2013 Ch.4 §II.A).
    vignetting_edge : float
        Extra (mechanical / optical) fall-off: the fraction of light lost at the image corner,
        with a (r / r_corner)^2 profile, in [0, 1).
    """

    aperture_area_m2: float
    transmission: float = 1.0
    psf_sigma_px: float = 1.0
    zero_point_photons_s_m2: float = V_MAG0_PHOTONS_S_M2
    psf: str = "gaussian"
    airy_first_zero_px: float | None = None
    field_curvature: float = 0.0
    natural_vignetting: bool = False
    vignetting_edge: float = 0.0

    def __post_init__(self) -> None:
        for name in ("aperture_area_m2", "psf_sigma_px", "zero_point_photons_s_m2"):
            object.__setattr__(self, name, _checks.positive(name, getattr(self, name)))
        transmission = _checks.fraction("transmission", self.transmission)
        object.__setattr__(self, "transmission", transmission)
        if self.psf not in ("gaussian", "airy"):
            raise InvalidInputError(f"psf must be 'gaussian' or 'airy', got {self.psf!r}")
        if self.airy_first_zero_px is not None:
            value = _checks.positive("airy_first_zero_px", self.airy_first_zero_px)
            object.__setattr__(self, "airy_first_zero_px", value)
        curvature = _checks.positive("field_curvature", self.field_curvature, allow_zero=True)
        object.__setattr__(self, "field_curvature", curvature)
        edge = _checks.positive("vignetting_edge", self.vignetting_edge, allow_zero=True)
        if edge >= 1.0:
            raise InvalidInputError(f"vignetting_edge must be in [0, 1), got {self.vignetting_edge!r}")
        object.__setattr__(self, "vignetting_edge", edge)
        object.__setattr__(self, "natural_vignetting", bool(self.natural_vignetting))

    @classmethod
    def from_diameter(cls, aperture_diameter_m: float, **kwargs) -> Optics:
        """Optics with a circular clear aperture of the given diameter (m)."""
        d = _checks.positive("aperture_diameter_m", aperture_diameter_m)
        return cls(aperture_area_m2=math.pi * d * d / 4.0, **kwargs)

    @property
    def aperture_diameter_m(self) -> float:
        """Diameter of the circular aperture with the same area, in m."""
        return math.sqrt(4.0 * self.aperture_area_m2 / math.pi)


@dataclass(frozen=True)
class Detector:
    """The image sensor and its read-out chain.

    Parameters
    ----------
    quantum_efficiency : float
        Electrons per photon reaching the detector (fill factor included), in (0, 1].
    gain_e_per_adu : float
        Conversion gain, electrons per ADU (Huffman 2006 §3.2.4 "Delta").
    read_noise_e : float
        Read noise, electrons rms per pixel (Huffman 2006 eq. 3.14).
    dark_current_e_s : float
        Dark current, electrons per second per pixel (Huffman 2006 eq. 3.8).
    bias_adu : float
        Constant offset added by the ADC, in ADU.
    full_well_e : float
        Pixel capacity in electrons; charge above it is lost (saturation).
    bit_depth : int
        ADC resolution, 1 to 16 bits; quantised values lie in [0, 2**bit_depth - 1].
    prnu_rms : float
        Photo-response non-uniformity: rms of the per-pixel gain about 1 (fraction, >= 0).
    dsnu_rms : float
        Dark-signal non-uniformity: rms of the per-pixel dark current about its mean (fraction).
    hot_pixel_fraction, dead_pixel_fraction : float
        Fractions of pixels that are hot (dark current ``hot_pixel_dark_e_s``) or dead (no
        response, no dark current: they read bias + read noise), in [0, 1].
    hot_pixel_dark_e_s : float
        Dark current of a hot pixel, electrons per second.
    pixel_map_seed : int
        Seed of the fixed-pattern maps (:mod:`._detector`): one sensor, one map, frame after frame.
    """

    quantum_efficiency: float = 1.0
    gain_e_per_adu: float = 1.0
    read_noise_e: float = 0.0
    dark_current_e_s: float = 0.0
    bias_adu: float = 0.0
    full_well_e: float = 1e5
    bit_depth: int = 16
    prnu_rms: float = 0.0
    dsnu_rms: float = 0.0
    hot_pixel_fraction: float = 0.0
    hot_pixel_dark_e_s: float = 1000.0
    dead_pixel_fraction: float = 0.0
    pixel_map_seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "quantum_efficiency",
                           _checks.fraction("quantum_efficiency", self.quantum_efficiency))
        for name in ("gain_e_per_adu", "full_well_e"):
            object.__setattr__(self, name, _checks.positive(name, getattr(self, name)))
        for name in ("read_noise_e", "dark_current_e_s", "bias_adu", "prnu_rms", "dsnu_rms",
                     "hot_pixel_fraction", "hot_pixel_dark_e_s", "dead_pixel_fraction"):
            value = _checks.positive(name, getattr(self, name), allow_zero=True)
            object.__setattr__(self, name, value)
        if self.hot_pixel_fraction + self.dead_pixel_fraction > 1.0:
            raise InvalidInputError("hot_pixel_fraction + dead_pixel_fraction must be at most 1, got "
                                    f"{self.hot_pixel_fraction} + {self.dead_pixel_fraction}")
        if not (isinstance(self.pixel_map_seed, int | np.integer) and self.pixel_map_seed >= 0):
            raise InvalidInputError(f"pixel_map_seed must be a whole number >= 0, got {self.pixel_map_seed!r}")
        if not (isinstance(self.bit_depth, int | np.integer) and 1 <= self.bit_depth <= 16):
            raise InvalidInputError(
                f"bit_depth must be an integer from 1 to 16, got {self.bit_depth!r}")

    @property
    def max_adu(self) -> int:
        """Largest value the ADC can output."""
        return 2 ** int(self.bit_depth) - 1


@dataclass(frozen=True)
class Sensor:
    """Optics, detector and exposure time: everything that turns magnitudes into ADU.

    Parameters
    ----------
    optics : Optics
    detector : Detector
    exposure_s : float
        Integration time in seconds.
    name, source : str
        A label and where the numbers come from.
    passband : Passband or None
        Relative spectral response of optics + detector; None is the V band (every star's colour
        factor is 1, the behaviour of the seeds).
    """

    optics: Optics
    detector: Detector = field(default_factory=Detector)
    exposure_s: float = 0.1
    name: str = ""
    source: str = ""
    passband: Passband | None = None

    def __post_init__(self) -> None:
        for name, kind in (("optics", Optics), ("detector", Detector)):
            if not isinstance(getattr(self, name), kind):
                raise InvalidInputError(f"{name} must be a {kind.__name__}, "
                                        f"got {type(getattr(self, name)).__name__}")
        object.__setattr__(self, "exposure_s", _checks.positive("exposure_s", self.exposure_s))
        if self.passband is not None and not isinstance(self.passband, Passband):
            raise InvalidInputError(f"passband must be a Passband or None, got {self.passband!r}")

    @property
    def psf_sigma_px(self) -> float:
        return self.optics.psf_sigma_px

    @property
    def dark_e(self) -> float:
        """Expected dark electrons per pixel in one exposure."""
        return self.detector.dark_current_e_s * self.exposure_s

    def with_exposure(self, exposure_s: float) -> Sensor:
        """The same sensor with another integration time."""
        return replace(self, exposure_s=exposure_s)

    def electrons(self, mag: ArrayLike, b_v: ArrayLike | None = None) -> NDArray[np.float64]:
        """Expected signal electrons of stars of V magnitude ``mag`` in one exposure.

        ``b_v`` (same shape, NaN allowed) applies the colour factor of :attr:`passband`; it is
        ignored without a passband (V band).
        """
        optics = self.optics
        electrons = electrons_from_magnitude(
            mag, aperture_area_m2=optics.aperture_area_m2, exposure_s=self.exposure_s,
            transmission=optics.transmission, quantum_efficiency=self.detector.quantum_efficiency,
            zero_point_photons_s_m2=optics.zero_point_photons_s_m2)
        return electrons * self.colour_factor(b_v)

    def colour_factor(self, b_v: ArrayLike | None) -> NDArray[np.float64] | float:
        """Sensor-band photons per V-band photon for colour ``b_v`` (1 without a passband)."""
        if self.passband is None:
            return 1.0
        return self.passband.colour_factor(np.nan if b_v is None else b_v)


def photon_flux_from_magnitude(mag: ArrayLike,
                               zero_point_photons_s_m2: float = V_MAG0_PHOTONS_S_M2
                               ) -> NDArray[np.float64]:
    """Photons s^-1 m^-2 at the top of the optics from stars of magnitude ``mag`` (any shape)."""
    return zero_point_photons_s_m2 * 10.0 ** (-0.4 * np.asarray(mag, dtype=float))


def electrons_from_magnitude(mag: ArrayLike, *, aperture_area_m2: float, exposure_s: float,
                             transmission: float = 1.0, quantum_efficiency: float = 1.0,
                             zero_point_photons_s_m2: float = V_MAG0_PHOTONS_S_M2
                             ) -> NDArray[np.float64]:
    """Expected signal electrons from stars of magnitude ``mag`` (any shape) in one exposure.

    ``PHI_0 * 10**(-0.4 mag) * area * transmission * QE * exposure``: Huffman 2006 §3.1 eq. 3.4 with
    the physical zero point of this module's docstring in place of the seed's "28".

    Raises
    ------
    InvalidInputError
        If a parameter is not positive and finite or a magnitude is not finite.
    """
    m = np.asarray(mag, dtype=float)
    if not np.all(np.isfinite(m)):
        raise InvalidInputError("mag must be finite magnitudes (got NaN or inf)")
    scale = (_checks.positive("aperture_area_m2", aperture_area_m2)
             * _checks.positive("exposure_s", exposure_s)
             * _checks.fraction("transmission", transmission)
             * _checks.fraction("quantum_efficiency", quantum_efficiency))
    zp = _checks.positive("zero_point_photons_s_m2", zero_point_photons_s_m2)
    return photon_flux_from_magnitude(m, zp) * scale


def magnitude_from_electrons(electrons: ArrayLike, sensor: Sensor) -> NDArray[np.float64]:
    """The V magnitude that gives ``electrons`` in one exposure of ``sensor`` (inverse of above)."""
    e = np.asarray(electrons, dtype=float)
    return -2.5 * np.log10(e / sensor.electrons(0.0))


# --- presets from the seeds ------------------------------------------------------------------
_FFSR_A_W = 0.12
_QE_FROM_FFSR = _FFSR_A_W * 1239.84198 / V_BAND_CENTER_NM  # R = QE * e * lambda / (h c) -> 0.27

HUFFMAN2006_EQ34_ZERO_POINT_PHOTONS_S_M2: float = (
    _FFSR_A_W * 10.0 * 10.0 ** (28.0 / 2.5) / _QE_FROM_FFSR)
"""The zero point that makes this model equal Huffman 2006 eq. 3.4 literally (FFSR 0.12 A/W, g = 10,
zero point "28"): 7.0e11 photons s^-1 m^-2, 80 times the V-band value. That scale is
about 10 times too bright for the seed's own detection results (our reading of Huffman 2006); use it
only to reproduce the seed's tables."""

_FAR_MST = Sensor(
    optics=Optics(aperture_area_m2=1.77e-4, transmission=1.0, psf_sigma_px=2.5),
    detector=Detector(quantum_efficiency=_QE_FROM_FFSR, gain_e_per_adu=10.0,
                      read_noise_e=39.0, dark_current_e_s=410.0, bias_adu=20.0,
                      full_well_e=120_000.0, bit_depth=10),
    exposure_s=0.1,
    name="far-mst",
    source=("Huffman 2006 Table 7.1 (p.127): lens area 1.77 cm^2, "
            "gain 10 e-/ADU, read noise 39 e-, dark 410 e-/s, t = 0.1 s, PSF width 10 px "
            "(sigma 2.5); QE 0.27 = FFSR 0.12 A/W at 550 nm; full well 120 000 e- and 10-bit "
            "ADC from §3.2.4 (IBIS5-A-1300). Assumed (not in the seed): transmission 1 "
            "(eq. 3.4 has no optics loss), bias 20 ADU (keeps read noise off the ADC floor). "
            "Physical V-band zero point."),
)

_GENERIC_CMOS = Sensor(
    optics=Optics.from_diameter(0.025, transmission=0.8, psf_sigma_px=1.0),
    detector=Detector(quantum_efficiency=0.6, gain_e_per_adu=1.0, read_noise_e=5.0,
                      dark_current_e_s=20.0, bias_adu=100.0, full_well_e=30000.0, bit_depth=12),
    exposure_s=0.2, name="generic-cmos",
    source="ours: a present-day CMOS star tracker (25 mm aperture, QE 0.6, 5 e- read noise, "
           "0.2 s), the default of the demo and the end-to-end tests; sees to about V 7.5")

SENSOR_PRESETS: dict[str, Sensor] = {
    "generic-cmos": _GENERIC_CMOS,
    "far-mst": _FAR_MST,
    "far-mst-seed-eq34": replace(
        _FAR_MST,
        optics=replace(_FAR_MST.optics,
                       zero_point_photons_s_m2=HUFFMAN2006_EQ34_ZERO_POINT_PHOTONS_S_M2),
        name="far-mst-seed-eq34",
        source="as 'far-mst', with the signal scale of Huffman 2006 eq. 3.4 taken literally "
               "(M_V 6 -> 1.34e4 e-); for reproducing the seed's tables only"),
}


def get_sensor_preset(name: str) -> Sensor:
    """A named sensor from the seeds (see :data:`SENSOR_PRESETS` for names and sources)."""
    key = preset_key(name)
    if key not in SENSOR_PRESETS:
        raise InvalidInputError(
            f"unknown sensor preset {name!r}; valid presets: {', '.join(sorted(SENSOR_PRESETS))}")
    return SENSOR_PRESETS[key]
