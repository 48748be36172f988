"""Detector noise and read-out: expected electrons in, ADU out.

The noise terms are those of seed 000 §3.2 (notes ``seed-000.md`` §1.3), applied in the order the
charge meets them:

1. expected electrons per pixel = signal + background + dark (``dark_current_e_s * exposure_s``);
2. **shot noise**: a Poisson draw of that expectation (signal, background and dark are all
   Poisson, eqs. 3.7-3.8);
3. **full well**: charge above ``full_well_e`` is lost (saturation, no blooming);
4. **read noise**: Gaussian, ``read_noise_e`` rms (eq. 3.14);
5. conversion to ADU by ``gain_e_per_adu`` and the **bias** offset;
6. **quantisation**: rounding to the nearest integer (seed §3.2.4's example: 0-58 e- read as 0 at
   117 e-/ADU), clipped to the ADC range [0, 2**bit_depth - 1], stored as uint16. Without
   quantisation the image stays float64 and, if ``saturate``, is clipped at the top of the range.

Every term can be switched off through :class:`NoiseModel`; with all of them off the image is the
expectation ``(signal + background + dark) / gain + bias``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from . import _checks
from .radiometry import Sensor


@dataclass(frozen=True)
class NoiseModel:
    """Which detector effects to apply (all on by default).

    Attributes
    ----------
    shot : bool
        Poisson noise on signal + background + dark.
    dark : bool
        Add the dark-current charge at all (its mean; its noise comes with ``shot``).
    read : bool
        Gaussian read noise.
    bias : bool
        The ADC bias offset.
    quantize : bool
        Round to integers and clip to the ADC range; output uint16.
    saturate : bool
        Clip charge at the full well (and, unquantised, ADU at the ADC maximum).
    """

    shot: bool = True
    dark: bool = True
    read: bool = True
    bias: bool = True
    quantize: bool = True
    saturate: bool = True

    @classmethod
    def ideal(cls) -> NoiseModel:
        """No random terms, no quantisation, no clipping: the expected image, dark and bias kept."""
        return cls(shot=False, read=False, quantize=False, saturate=False)

    @classmethod
    def coerce(cls, noise: bool | NoiseModel) -> NoiseModel:
        """``True`` -> everything on, ``False`` -> :meth:`ideal`, a NoiseModel as it is."""
        if isinstance(noise, NoiseModel):
            return noise
        if isinstance(noise, bool | np.bool_):
            return cls() if noise else cls.ideal()
        raise InvalidInputError(f"noise must be True, False or a NoiseModel, got {noise!r}")


def expected_electrons(signal_e: NDArray[np.float64], sensor: Sensor, background_e: ArrayLike = 0.0,
                       *, dark: bool = True) -> NDArray[np.float64]:
    """Expected electrons per pixel (signal + background + dark): a new array like ``signal_e``."""
    background = np.asarray(background_e, dtype=float)
    if not _checks.finite_nonnegative(background):
        raise InvalidInputError("background_e must be finite and >= 0 electrons per pixel")
    try:
        fits = np.broadcast_shapes(background.shape, signal_e.shape) == signal_e.shape
    except ValueError:
        fits = False
    if not fits:
        raise InvalidInputError(f"background_e of shape {background.shape} does not broadcast "
                                f"to the image shape {signal_e.shape}")
    total = signal_e + background
    if dark:
        total += sensor.dark_e
    return total


def read_out(signal_e: ArrayLike, sensor: Sensor, *, background_e: ArrayLike = 0.0,
             noise: bool | NoiseModel = True,
             rng: np.random.Generator | int | None = None) -> NDArray:
    """The image a detector reads out from an expected-signal image.

    Parameters
    ----------
    signal_e : array_like, shape (H, W)
        Expected star electrons per pixel (noise-free), e.g. from
        :func:`startrack.simulate.psf.render_gaussian_psf`.
    sensor : Sensor
        Detector parameters and exposure time.
    background_e : float or array_like broadcastable to (H, W)
        Expected sky / stray-light electrons per pixel in the exposure.
    noise : bool or NoiseModel
        Which terms to apply (see :class:`NoiseModel`).
    rng : numpy.random.Generator, int or None
        Source of the Poisson and Gaussian draws (Poisson first, then Gaussian).

    Returns
    -------
    ndarray, shape (H, W)
        ADU; uint16 when quantised, float64 otherwise.
    """
    model = NoiseModel.coerce(noise)
    signal = np.asarray(signal_e, dtype=float)
    if signal.ndim != 2 or not _checks.finite_nonnegative(signal):
        raise InvalidInputError("signal_e must be a 2-D array of finite electrons >= 0")
    det = sensor.detector
    rng = np.random.default_rng(rng)
    electrons = expected_electrons(signal, sensor, background_e, dark=model.dark)  # a new array
    if model.shot:
        electrons = rng.poisson(electrons).astype(float)
    if model.saturate:
        np.minimum(electrons, det.full_well_e, out=electrons)
    if model.read and det.read_noise_e > 0:
        read = rng.standard_normal(size=electrons.shape)
        read *= det.read_noise_e
        electrons += read
    electrons /= det.gain_e_per_adu
    if model.bias:
        electrons += det.bias_adu
    return _digitise(electrons, det.max_adu, model)


def _digitise(adu: NDArray[np.float64], max_adu: int, model: NoiseModel) -> NDArray:
    """Round and clip to the ADC range (uint16), or only clip at the top when saturating.

    Works in place on ``adu``.
    """
    if model.quantize:
        adu += 0.5
        np.floor(adu, out=adu)
        np.clip(adu, 0, max_adu, out=adu)
        return adu.astype(np.uint16)
    if model.saturate:
        np.minimum(adu, float(max_adu), out=adu)
    return adu
