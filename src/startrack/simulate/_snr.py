"""Analytic companions of the simulator: SNR of a star, limiting magnitude, smear-limited rate.

**SNR** (Huffman 2006 §3.2, eq. 3.17) of a star measured by summing a
square box of ``box_px`` x ``box_px`` pixels centred on it, the known background subtracted::

    SNR = S_box / sqrt(S_box + n (B + D + R^2 + Q^2)),      Q^2 = g^2 / 12

with S_box the star's electrons inside the box (the pixel-integrated Gaussian PSF centred on a
pixel puts ``erf(box / (2 sqrt(2) sigma))^2`` of its light there), n = box^2 pixels, B the sky
electrons per pixel, D the dark electrons per pixel, R the read noise (e-) and g the gain
(e-/ADU; the quantisation noise of Huffman 2006 eqs. 3.9-3.13). Each term can be left out, matching
the switches of :class:`startrack.simulate._noise.NoiseModel`. The **peak-pixel SNR** of eq. 3.18
is the star's light in its brightest pixel over the per-pixel noise.

**Limiting magnitude**: the magnitude whose SNR equals a target, from the quadratic
``S^2 = k^2 (S + N0)``.

**Smear limit** (Samaan 2002, "Maximum Angular Rate Estimation", Table 1
§2.3): the image moves less than ``fraction_px`` of a pixel during the exposure when
``omega < fraction_px * IFOV / t``. IFOV is the angle of one pixel: ``1 / fx`` at the boresight
(``ifov="center"``) or the field of view over the pixel count (``ifov="mean"``, the seed's
reading: 8 deg / 512 px for Table 1).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import erf

from ..camera import Camera
from ..errors import InvalidInputError
from . import _checks
from ._noise import NoiseModel
from ._radiometry import Sensor, magnitude_from_electrons


def default_box_px(sensor: Sensor) -> int:
    """An odd box side that holds about 90 % of a Gaussian star's light: 2 ceil(2 sigma) + 1."""
    return 2 * math.ceil(2.0 * sensor.psf_sigma_px) + 1


def box_fraction(sigma_px: float, box_px: int) -> float:
    """Fraction of a pixel-integrated Gaussian, centred on a pixel, inside a box of side ``box_px``."""
    return float(erf(box_px / (2.0 * math.sqrt(2.0) * sigma_px))) ** 2


def noise_per_pixel_e2(sensor: Sensor, background_e: float = 0.0,
                       noise: bool | NoiseModel = True) -> float:
    """Variance (e^2) of one star-free pixel: background + dark shot noise, read, quantisation."""
    model = NoiseModel.coerce(noise)
    det = sensor.detector
    var = 0.0
    if model.shot:
        var += (background_e if model.background else 0.0) + (sensor.dark_e if model.dark else 0.0)
    if model.read:
        var += det.read_noise_e**2
    if model.quantize:
        var += det.gain_e_per_adu**2 / 12.0
    return var


def star_snr(mag: ArrayLike, sensor: Sensor, *, box_px: int | None = None, background_e: float = 0.0,
             b_v: ArrayLike | None = None, noise: bool | NoiseModel = True) -> NDArray[np.float64]:
    """SNR of stars of V magnitude ``mag`` summed in a ``box_px`` box (see the module docstring).

    Parameters
    ----------
    mag : array_like
    sensor : Sensor
    box_px : int, optional
        Odd side of the square box (default :func:`default_box_px`).
    background_e : float
        Sky electrons per pixel in the exposure.
    b_v : array_like, optional
        Colours, for a sensor with a passband.
    noise : bool or NoiseModel
        Which noise terms count (shot noise of the star itself with ``shot``).
    """
    box = _box(sensor, box_px)
    model = NoiseModel.coerce(noise)
    signal = sensor.electrons(mag, b_v) * box_fraction(sensor.psf_sigma_px, box)
    background = _checks.positive("background_e", background_e, allow_zero=True)
    var: float | NDArray[np.float64] = box * box * noise_per_pixel_e2(sensor, background, model)
    if model.shot:
        var = var + signal
    with np.errstate(divide="ignore"):
        return signal / np.sqrt(var)


def peak_snr(mag: ArrayLike, sensor: Sensor, *, background_e: float = 0.0, b_v: ArrayLike | None = None,
             noise: bool | NoiseModel = True, star_shot_noise: bool = False) -> NDArray[np.float64]:
    """Huffman 2006 eq. 3.18: the star's light in its peak pixel (centred) over the pixel noise.

    ``star_shot_noise`` adds the star's own shot noise to the denominator (the seed leaves it out).
    """
    peak = sensor.electrons(mag, b_v) * box_fraction(sensor.psf_sigma_px, 1)
    var = noise_per_pixel_e2(sensor, background_e, noise) + (peak if star_shot_noise else 0.0)
    return peak / np.sqrt(var)


def limiting_magnitude(snr: float, sensor: Sensor, *, box_px: int | None = None, background_e: float = 0.0,
                       b_v: float | None = None, noise: bool | NoiseModel = True) -> float:
    """The V magnitude whose :func:`star_snr` equals ``snr``."""
    k = _checks.positive("snr", snr)
    box = _box(sensor, box_px)
    model = NoiseModel.coerce(noise)
    n0 = box * box * noise_per_pixel_e2(sensor, background_e, model)
    if model.shot:
        in_box = 0.5 * (k * k + math.sqrt(k**4 + 4.0 * k * k * n0))
    else:
        in_box = k * math.sqrt(n0)
    if in_box <= 0:
        raise InvalidInputError("with every noise term off the SNR is infinite: no limiting magnitude")
    electrons = in_box / box_fraction(sensor.psf_sigma_px, box) / float(sensor.colour_factor(b_v))
    return float(magnitude_from_electrons(electrons, sensor))


def ifov_rad(camera: Camera, ifov: str = "center") -> float:
    """Angle of one pixel: ``1 / fx`` ("center") or horizontal FOV / width ("mean")."""
    if ifov == "center":
        return 1.0 / camera.fx
    if ifov == "mean":
        return math.radians(camera.fov_deg) / camera.width
    raise InvalidInputError(f"ifov must be 'center' or 'mean', got {ifov!r}")


def max_rate_rad_s(camera: Camera, exposure_s: float, fraction_px: float = 0.1, ifov: str = "center") -> float:
    """Largest angular rate (rad/s, across the boresight) that smears a star by at most
    ``fraction_px`` pixels in ``exposure_s`` (Samaan 2002 Table 1 uses 0.1 px)."""
    t = _checks.positive("exposure_s", exposure_s)
    return _checks.positive("fraction_px", fraction_px) * ifov_rad(camera, ifov) / t


def _box(sensor: Sensor, box_px: int | None) -> int:
    box = default_box_px(sensor) if box_px is None else box_px
    if not (isinstance(box, int | np.integer) and box >= 1 and box % 2 == 1):
        raise InvalidInputError(f"box_px must be an odd whole number of pixels >= 1, got {box_px!r}")
    return int(box)
