"""Sky background per pixel: zodiacal light and the diffuse sky, plus stray light.

A surface brightness ``mu`` (V mag per square arcsecond) sends ``PHI_0 10^(-0.4 mu)`` photons
s^-1 m^-2 per arcsec^2 (the V-band zero point of :mod:`._radiometry`), so a pixel of solid angle
``omega_px`` (arcsec^2, 1 / (fx fy) rad^2 on the axis) collects

    e_px = PHI_0 10^(-0.4 mu) omega_px * aperture * transmission * QE * t * colour(B-V = 0.65)

electrons (the zodiacal light is scattered sunlight, so a sensor band other than V sees it with
the Sun's colour). Natural and mechanical vignetting shape it across the field
(:func:`.optics.background_illumination`). Stray light (baffle scatter, Huffman 2006 §3.2's
"background ... stray light, Sun glint") is given directly in electrons per second per pixel,
optionally with a linear gradient across the image.

The zodiacal light depends mostly on the ecliptic latitude beta of the view direction. As a
coarse model (ours, +-30 %; see Leinert et al. 1998, A&AS 127, 1 for the real tables) we take,
away from the Sun (elongation > 90 deg), ``60 + 200 cos^4(beta)`` S10 units, where one S10 is one
V = 10 star per square degree (27.78 mag arcsec^-2): 23.3 mag arcsec^-2 at the ecliptic poles
(the darkest sky seen from space) and 21.7 in the ecliptic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import Camera
from ..errors import InvalidInputError
from . import _checks
from ._optics import background_illumination
from ._passband import SUN_B_V
from ._radiometry import Sensor

S10_MAG_ARCSEC2: float = 10.0 + 2.5 * math.log10(3600.0**2)
"""Surface brightness of one S10 unit (a V = 10 star per square degree), mag arcsec^-2."""
OBLIQUITY_J2000_RAD: float = math.radians(23.4392911)
ECLIPTIC_POLE_ICRS = np.array([0.0, -math.sin(OBLIQUITY_J2000_RAD), math.cos(OBLIQUITY_J2000_RAD)])
ARCSEC2_PER_SR: float = (180.0 * 3600.0 / math.pi) ** 2


def ecliptic_latitude(v_icrs: ArrayLike) -> NDArray[np.float64]:
    """Ecliptic latitude (rad) of ICRS directions (..., 3) (mean ecliptic of J2000)."""
    v = np.asarray(v_icrs, dtype=float)
    s = np.sum(v * ECLIPTIC_POLE_ICRS, axis=-1) / np.linalg.norm(v, axis=-1)
    return np.arcsin(np.clip(s, -1.0, 1.0))


def zodiacal_mag_arcsec2(ecliptic_lat_rad: ArrayLike) -> NDArray[np.float64]:
    """Coarse zodiacal-light surface brightness (V mag arcsec^-2) at an ecliptic latitude."""
    c = np.cos(np.asarray(ecliptic_lat_rad, dtype=float))
    s10 = 60.0 + 200.0 * c**4
    return S10_MAG_ARCSEC2 - 2.5 * np.log10(s10)


@dataclass(frozen=True)
class SkyBackground:
    """Diffuse light on the detector.

    Parameters
    ----------
    mag_arcsec2 : float or None
        Surface brightness of the sky (zodiacal light + diffuse galactic light), V mag arcsec^-2;
        None for none. :meth:`zodiacal` picks it from the view direction.
    stray_e_s_px : float
        Stray light, electrons per second per pixel at the image centre (>= 0).
    stray_gradient : float
        Fractional change of the stray light from the image centre to the edge along
        ``stray_direction_deg`` (|g| <= 1): half the longer side away from the centre. Along a
        diagonal the corners lie farther than that; where a steep gradient would take the light
        below zero there, it is zero.
    stray_direction_deg : float
        Direction of the gradient in the image, degrees from +x towards +y.
    """

    mag_arcsec2: float | None = 22.5
    stray_e_s_px: float = 0.0
    stray_gradient: float = 0.0
    stray_direction_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.mag_arcsec2 is not None and not math.isfinite(float(self.mag_arcsec2)):
            raise InvalidInputError(f"mag_arcsec2 must be a finite magnitude or None, got {self.mag_arcsec2!r}")
        object.__setattr__(self, "stray_e_s_px", _checks.positive("stray_e_s_px", self.stray_e_s_px,
                                                                  allow_zero=True))
        if not (math.isfinite(self.stray_gradient) and abs(self.stray_gradient) <= 1.0):
            raise InvalidInputError(f"stray_gradient must be in [-1, 1], got {self.stray_gradient!r}")

    @classmethod
    def zodiacal(cls, boresight_icrs: ArrayLike, **stray) -> SkyBackground:
        """The coarse zodiacal model for a boresight direction, plus optional stray light."""
        return cls(mag_arcsec2=float(zodiacal_mag_arcsec2(ecliptic_latitude(boresight_icrs))), **stray)

    def sky_electrons_px(self, camera: Camera, sensor: Sensor) -> float:
        """Sky electrons per pixel on the axis in one exposure (no vignetting)."""
        if self.mag_arcsec2 is None:
            return 0.0
        omega_arcsec2 = ARCSEC2_PER_SR / (camera.fx * camera.fy)
        per_arcsec2 = sensor.electrons(self.mag_arcsec2, np.array(SUN_B_V))
        return float(per_arcsec2 * omega_arcsec2)

    def electrons(self, camera: Camera, sensor: Sensor) -> float | NDArray[np.float64]:
        """Expected background electrons per pixel in one exposure: a scalar or (H, W)."""
        sky = self.sky_electrons_px(camera, sensor) * background_illumination(camera, sensor.optics)
        stray: float | NDArray[np.float64] = self.stray_e_s_px * sensor.exposure_s
        if stray > 0 and self.stray_gradient != 0.0:
            stray = stray * self._gradient(camera)
        total = sky + stray
        return float(total) if np.ndim(total) == 0 else total

    def _gradient(self, camera: Camera) -> NDArray[np.float64]:
        angle = math.radians(self.stray_direction_deg)
        ys, xs = np.mgrid[0:camera.height, 0:camera.width].astype(float)
        along = (xs - camera.cx) * math.cos(angle) + (ys - camera.cy) * math.sin(angle)
        half = 0.5 * max(camera.width, camera.height)
        return np.maximum(1.0 + self.stray_gradient * along / half, 0.0)  # no negative light
