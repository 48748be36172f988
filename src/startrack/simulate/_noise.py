"""Detector noise and read-out: expected electrons in, ADU out.

The noise terms are those of Huffman 2006 §3.2, applied in the order the
charge meets them, with the fixed-pattern effects of :mod:`._detector` (Fowler 2013 Ch.3):

1. expected electrons per pixel = (signal + sky background) x response (PRNU; 0 if dead)
   + dark current x time (x DSNU; a hot pixel's own rate; 0 if dead);
2. **shot noise**: a Poisson draw of that expectation (signal, background and dark are all
   Poisson, eqs. 3.7-3.8);
3. **full well**: charge above ``full_well_e`` is lost (saturation), or with ``blooming`` spills
   along the column (:func:`.detector.bloom`);
4. **read noise**: Gaussian, ``read_noise_e`` rms (eq. 3.14);
5. conversion to ADU by ``gain_e_per_adu`` and the **bias** offset;
6. **quantisation**: rounding to the nearest integer (seed §3.2.4's example: 0-58 e- read as 0 at
   117 e-/ADU), clipped to the ADC range [0, 2**bit_depth - 1], stored as uint16. Without
   quantisation the image stays float64 and, if ``saturate``, is clipped at the top of the range.

Every term can be switched off through :class:`NoiseModel`; with all of them off the image is the
expectation ``(signal + background + dark) / gain + bias``.

Speed. Drawing a Poisson number per pixel is the cost of a frame (docs/simulation.md gives the
measured figure). Most pixels of a star image share one expectation (sky + dark), and for them steps 2-6 give one
discrete distribution of ADU values, which :func:`readout_table` computes exactly (Poisson
probabilities times the normal probability of each rounding interval); those pixels are drawn
from it by inverse-transform sampling with a guide table (one uniform number each). Pixels with
any other expectation (stars, hot and dead pixels) go through steps 2-6 one by one. Both are exact
draws of the same per-pixel distribution (tests compare them); the table is used when the output
is quantised, without blooming, PRNU or DSNU, and when at most a quarter of the pixels differ
from the common level.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import norm, poisson

from ..errors import InvalidInputError, as_float_array, checked_rng
from . import _checks
from ._detector import PixelMaps, bloom, pixel_maps
from ._radiometry import Detector, Sensor

TABLE_MAX_ENTRIES = 4_000_000
"""Largest (charges x ADU values) table computed for the fast path; larger levels go pixel by pixel."""
_TAIL_SIGMAS = 13.0

MAX_EXPECTED_E = 1e18
"""The largest charge a pixel may expect in one exposure (electrons). numpy draws Poisson counts up to
about 9.2e18; real full wells hold under 1e7 e-, so only a mistaken setting (an exposure of years, an
aperture of square kilometres, a PRNU of thousands) expects more."""


@dataclass(frozen=True)
class NoiseModel:
    """Which detector effects to apply (all on by default, blooming off).

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
    background : bool
        Add the sky / stray-light background given to the read-out.
    prnu, dsnu, hot_pixels, dead_pixels : bool
        The fixed-pattern effects of :mod:`._detector` (they act only when the detector has them).
    blooming : bool
        Spill charge above the full well along the columns instead of losing it (needs
        ``saturate``).
    """

    shot: bool = True
    dark: bool = True
    read: bool = True
    bias: bool = True
    quantize: bool = True
    saturate: bool = True
    background: bool = True
    prnu: bool = True
    dsnu: bool = True
    hot_pixels: bool = True
    dead_pixels: bool = True
    blooming: bool = False

    @classmethod
    def ideal(cls) -> NoiseModel:
        """No random terms, no fixed pattern, no quantisation, no clipping: the expected image,
        with dark, background and bias kept."""
        return cls(shot=False, read=False, quantize=False, saturate=False, prnu=False, dsnu=False,
                   hot_pixels=False, dead_pixels=False)

    @classmethod
    def coerce(cls, noise: bool | NoiseModel) -> NoiseModel:
        """``True`` -> everything on, ``False`` -> :meth:`ideal`, a NoiseModel as it is."""
        if isinstance(noise, NoiseModel):
            return noise
        if isinstance(noise, bool | np.bool_):
            return cls() if noise else cls.ideal()
        raise InvalidInputError(f"noise must be True, False or a NoiseModel, got {noise!r}")


def _checked_background(background_e: ArrayLike, shape: tuple[int, ...]) -> NDArray[np.float64]:
    background = as_float_array(background_e, "background_e")
    if not _checks.finite_nonnegative(background):
        raise InvalidInputError("background_e must be finite and >= 0 electrons per pixel")
    try:
        fits = np.broadcast_shapes(background.shape, shape) == shape
    except ValueError:
        fits = False
    if not fits:
        raise InvalidInputError(f"background_e of shape {background.shape} does not broadcast "
                                f"to the image shape {shape}")
    return background


def expected_electrons(signal_e: NDArray[np.float64], sensor: Sensor, background_e: ArrayLike = 0.0,
                       *, dark: bool = True) -> NDArray[np.float64]:
    """Expected electrons per pixel (signal + background + dark), no fixed pattern: a new array."""
    total = signal_e + _checked_background(background_e, signal_e.shape)
    if dark:
        total += sensor.dark_e
    return total


def _active_maps(det: Detector, shape: tuple[int, int], model: NoiseModel) -> PixelMaps:
    """The detector's maps with the ones switched off (or absent) set to None."""
    maps = pixel_maps(det, shape)
    return PixelMaps(response=maps.response if model.prnu else None,
                     dark_scale=maps.dark_scale if model.dsnu and model.dark else None,
                     hot=maps.hot if model.hot_pixels and model.dark else None,
                     dead=maps.dead if model.dead_pixels else None)


def _expectation(light: NDArray, sensor: Sensor, maps: PixelMaps, model: NoiseModel,
                 index: NDArray[np.intp] | None = None) -> NDArray[np.float64]:
    """Expected electrons of the pixels ``index`` (flat) of ``light`` = signal + background.

    ``light`` is the full image (index None) or already the selected pixels (1-D); it is
    modified in place.
    """
    def pick(arr):
        return arr if index is None else arr.ravel()[index]

    if maps.response is not None:
        light *= pick(maps.response)
    dark: float | NDArray[np.float64]
    if not model.dark:
        dark = 0.0
    elif maps.dark_scale is not None:
        dark = sensor.dark_e * pick(maps.dark_scale)
    else:
        dark = sensor.dark_e
    if maps.hot is not None:  # hot pixels come only with the dark current (_active_maps)
        with_hot = np.array(np.broadcast_to(dark, light.shape), dtype=float)
        with_hot[pick(maps.hot)] = sensor.detector.hot_pixel_dark_e_s * sensor.exposure_s
        dark = with_hot
    light += dark
    if maps.dead is not None:
        light[pick(maps.dead)] = 0.0
    return light


def read_out(signal_e: ArrayLike, sensor: Sensor, *, background_e: ArrayLike = 0.0,
             noise: bool | NoiseModel = True,
             rng: np.random.Generator | int | None = None) -> NDArray:
    """The image a detector reads out from an expected-signal image.

    Parameters
    ----------
    signal_e : array_like, shape (H, W)
        Expected star electrons per pixel (noise-free), e.g. from
        :func:`startrack.simulate._psf.render_gaussian_psf`.
    sensor : Sensor
        Detector parameters (noise, fixed pattern) and exposure time.
    background_e : float or array_like broadcastable to (H, W)
        Expected sky / stray-light electrons per pixel in the exposure (before PRNU).
    noise : bool or NoiseModel
        Which terms to apply (see :class:`NoiseModel`).
    rng : numpy.random.Generator, int or None
        Source of the random draws; the same seed gives a bit-identical image.

    Returns
    -------
    ndarray, shape (H, W)
        ADU; uint16 when quantised, float64 otherwise.
    """
    model = NoiseModel.coerce(noise)
    signal = np.asarray(signal_e, dtype=float)
    if signal.ndim != 2 or not _checks.finite_nonnegative(signal):
        raise InvalidInputError("signal_e must be a 2-D array of finite electrons >= 0")
    background = _checked_background(background_e, signal.shape)
    if not model.background:
        background = np.zeros(())
    rng = checked_rng(rng)
    maps = _active_maps(sensor.detector, signal.shape, model)
    level = _common_level(background, sensor, maps, model)
    table = None if level is None else _table_or_none(level, sensor.detector, model)
    if table is not None:
        irregular = _irregular_pixels(signal, maps)
        if irregular.size <= signal.size // 4:
            sky = float(background.max(initial=0.0))
            return _read_out_table(signal, table, irregular, sky, sensor, maps, model, rng)
    electrons = _expectation(signal + background, sensor, maps, model)
    return _read_out_pixels(electrons, sensor.detector, model, rng, bloom_ok=True)


def _common_level(background: NDArray, sensor: Sensor, maps: PixelMaps, model: NoiseModel) -> float | None:
    """The expected electrons shared by star-free, defect-free pixels, or None if the table
    path does not apply (unquantised, blooming, PRNU, DSNU, a non-uniform background)."""
    if not model.quantize or (model.blooming and model.saturate):
        return None
    if maps.response is not None or maps.dark_scale is not None:
        return None
    if background.ndim and not (background.min() == background.max()):
        return None
    return float(background.max(initial=0.0)) + (sensor.dark_e if model.dark else 0.0)


def _irregular_pixels(signal: NDArray, maps: PixelMaps) -> NDArray[np.intp]:
    """Flat indices of the pixels whose expectation differs from the common level."""
    mask = signal > 0
    for defects in (maps.hot, maps.dead):
        if defects is not None:
            mask |= defects
    return np.flatnonzero(mask)


def check_expected_charge(peak_e: float) -> None:
    """Raise InvalidInputError when a pixel expects more than :data:`MAX_EXPECTED_E` electrons
    (``peak_e``, the largest expectation; NaN and inf too), naming the settings that make it."""
    if not peak_e <= MAX_EXPECTED_E:
        raise InvalidInputError(
            f"a pixel expects {peak_e:.3g} electrons in the exposure, more than the {MAX_EXPECTED_E:.0e} the "
            "simulator can draw: shorten the exposure or lower the aperture, the sky, the stray light, the dark "
            "current or the PRNU")


def _table_or_none(level_e: float, det: Detector, model: NoiseModel):
    check_expected_charge(level_e)
    try:
        return readout_table(level_e, det, model)
    except InvalidInputError:  # too bright a level for a table: pixel by pixel
        return None


def _read_out_table(signal, table, irregular, background, sensor, maps, model, rng) -> NDArray:
    """Fast path: every pixel drawn from the read-out table, then the irregular ones redone."""
    values, cdf, guide = table
    image = values[sample_table(cdf, guide, signal.size, rng)].reshape(signal.shape)
    if irregular.size:
        light = signal.ravel()[irregular] + background
        electrons = _expectation(light, sensor, maps, model, irregular)
        image.ravel()[irregular] = _read_out_pixels(electrons, sensor.detector, model, rng)
    return image


def _read_out_pixels(electrons: NDArray[np.float64], det: Detector, model: NoiseModel,
                     rng: np.random.Generator, bloom_ok: bool = False) -> NDArray:
    """Steps 2-6 on an array of expected electrons (any shape; 2-D for blooming); in place."""
    check_expected_charge(float(electrons.max(initial=0.0)))
    if model.shot:
        electrons = rng.poisson(electrons).astype(float)
    if model.saturate:
        if model.blooming and bloom_ok:
            bloom(electrons, det.full_well_e)
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


# --- the read-out distribution of one expectation, and sampling from it ----------------------
def _charge_distribution(level_e: float, det: Detector, model: NoiseModel
                         ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Charges (e-) after shot noise and the full well, and their probabilities."""
    if not model.shot:
        charge = np.array([level_e])
        prob = np.ones(1)
    else:
        spread = _TAIL_SIGMAS * np.sqrt(level_e) + 30.0
        if 2.0 * spread > TABLE_MAX_ENTRIES:  # before np.arange allocates it
            raise InvalidInputError(f"read-out table for {level_e:g} e- would be too large")
        charge = np.arange(max(0.0, np.floor(level_e - spread)), np.ceil(level_e + spread) + 1.0)
        prob = poisson.pmf(charge, level_e)
    if model.saturate:
        charge = np.minimum(charge, det.full_well_e)
    return charge, prob


@functools.lru_cache(maxsize=32)
def readout_table(level_e: float, det: Detector, model: NoiseModel
                  ) -> tuple[NDArray[np.uint16], NDArray[np.float64], NDArray[np.intp]]:
    """The exact distribution of the quantised ADU of a pixel expecting ``level_e`` electrons.

    Returns
    -------
    values : ndarray of uint16, shape (M,)
        Possible ADU values, increasing.
    cdf : ndarray, shape (M,)
        ``P(ADU <= values[m])``; the last entry is 1. Tail mass below 1e-30 is left out.
    guide : ndarray of int, shape (K + 1,)
        ``guide[j]`` = the index of the value at quantile j / K (for :func:`sample_table`).

    Raises
    ------
    InvalidInputError
        When the table would exceed :data:`TABLE_MAX_ENTRIES` (a very bright level).
    """
    charge, prob = _charge_distribution(level_e, det, model)
    bias = det.bias_adu if model.bias else 0.0
    sigma = det.read_noise_e if model.read else 0.0
    g = det.gain_e_per_adu
    lo = np.floor((charge.min() - _TAIL_SIGMAS * sigma) / g + bias) - 1.0
    hi = np.ceil((charge.max() + _TAIL_SIGMAS * sigma) / g + bias) + 1.0
    adu = np.arange(lo, hi + 1.0)
    if adu.size * charge.size > TABLE_MAX_ENTRIES:
        raise InvalidInputError(f"read-out table for {level_e:g} e- would be too large")
    if sigma > 0:
        edges = g * (np.append(adu - 0.5, adu[-1] + 0.5) - bias)  # charge + read noise limits
        cdf_k = norm.cdf((edges[None, :] - charge[:, None]) / sigma)
        pmf = prob @ np.diff(cdf_k, axis=1)
    else:
        index = np.floor(charge / g + bias + 0.5) - lo
        pmf = np.bincount(index.astype(np.intp), weights=prob, minlength=adu.size)
    values = np.clip(adu, 0, det.max_adu)
    uniq, inverse = np.unique(values, return_inverse=True)
    cdf = np.cumsum(np.bincount(inverse, weights=pmf))
    cdf = cdf / cdf[-1]
    return _frozen_table(uniq.astype(np.uint16), cdf)


def _frozen_table(values: NDArray, cdf: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    cdf[-1] = 1.0
    k = max(1024, 4 * cdf.size)
    guide = np.searchsorted(cdf, np.arange(k + 1) / k, side="right")
    guide = np.minimum(guide, cdf.size - 1)
    for arr in (values, cdf, guide):
        arr.flags.writeable = False
    return values, cdf, guide


def sample_table(cdf: NDArray[np.float64], guide: NDArray[np.intp], n: int,
                 rng: np.random.Generator) -> NDArray[np.intp]:
    """``n`` indices drawn with probabilities ``diff(cdf)`` (inverse transform, guide table).

    For a uniform u, the answer is the first m with u < cdf[m]; the guide gives a lower bound
    (the answer at quantile floor(u K) / K) and a few vectorised steps finish the search.
    """
    k = guide.size - 1
    u = rng.random(n)
    index = guide[(u * k).astype(np.intp)]
    todo = np.flatnonzero(u >= cdf[index])
    while todo.size:
        index[todo] += 1
        todo = todo[u[todo] >= cdf[index[todo]]]
    return index
