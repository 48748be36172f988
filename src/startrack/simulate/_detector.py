"""Real-sensor effects that are fixed per pixel, and blooming (Fowler 2013 Ch.3, Sease 2013 Eq. 2.10–2.11).

Fixed pattern (one map per sensor, drawn from ``Detector.pixel_map_seed`` and the image shape, so
every frame of a sequence sees the same map; cached):

- **PRNU**, photo-response non-uniformity: each pixel's response to light is ``1 + prnu_rms z``
  (z standard normal, clipped at 0);
- **DSNU**, dark-signal non-uniformity: each pixel's dark current is ``dark (1 + dsnu_rms z')``
  (clipped at 0); its dark charge is Poisson like any dark charge;
- **hot pixels**: a fraction of pixels with dark current ``hot_pixel_dark_e_s``;
- **dead pixels**: a fraction with no response and no dark current (they read bias + read noise).

Hot and dead pixels are drawn without overlap. **Blooming** (an option of
:class:`startrack.simulate._noise.NoiseModel`): charge above the full well spills along the
column, half up and half down, filling the next pixels to the full well and running on until it
is absorbed or leaves the detector (a CCD bleed trail; charge is conserved inside the image).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._radiometry import Detector


@dataclass(frozen=True, eq=False)
class PixelMaps:
    """Fixed-pattern maps of one detector at one image size (read-only arrays, or None).

    Attributes
    ----------
    response : ndarray (H, W) or None
        Relative response to light (PRNU); None when uniform (1).
    dark_scale : ndarray (H, W) or None
        Dark current relative to ``Detector.dark_current_e_s`` (DSNU); None when uniform (1).
    hot : ndarray of bool (H, W) or None
        Hot pixels (their dark current is ``hot_pixel_dark_e_s``), None when there are none.
    dead : ndarray of bool (H, W) or None
        Dead pixels (no response, no dark current), None when there are none.
    """

    response: NDArray[np.float64] | None
    dark_scale: NDArray[np.float64] | None
    hot: NDArray[np.bool_] | None
    dead: NDArray[np.bool_] | None


def _readonly(arr: NDArray) -> NDArray:
    arr.flags.writeable = False
    return arr


@functools.lru_cache(maxsize=8)
def pixel_maps(detector: Detector, shape: tuple[int, int]) -> PixelMaps:
    """The fixed-pattern maps of ``detector`` for images of ``shape`` (H, W); cached.

    The draws come from ``numpy.random.default_rng(detector.pixel_map_seed)`` in a fixed order
    (PRNU, DSNU, defects), so a map depends only on the detector settings and the shape.
    """
    rng = np.random.default_rng(detector.pixel_map_seed)
    shape = (int(shape[0]), int(shape[1]))
    response = dark_scale = hot = dead = None
    if detector.prnu_rms > 0:
        response = np.maximum(1.0 + detector.prnu_rms * rng.standard_normal(shape), 0.0)
    if detector.dsnu_rms > 0:
        dark_scale = np.maximum(1.0 + detector.dsnu_rms * rng.standard_normal(shape), 0.0)
    if detector.hot_pixel_fraction > 0 or detector.dead_pixel_fraction > 0:
        u = rng.random(shape)
        hot = u < detector.hot_pixel_fraction
        dead = (u >= detector.hot_pixel_fraction) & (
            u < detector.hot_pixel_fraction + detector.dead_pixel_fraction)
        hot = hot if hot.any() else None
        dead = dead if dead.any() else None
    return PixelMaps(*(None if a is None else _readonly(a) for a in (response, dark_scale, hot, dead)))


def bloom(charge_e: NDArray[np.float64], full_well_e: float) -> NDArray[np.float64]:
    """Spill charge above ``full_well_e`` along columns (axis 0), half each way; in place.

    Each over-full pixel keeps the full well and sends half of its excess down the column and
    half up; the excess fills the first pixels with room, passing over full ones. Each direction
    is one queue recursion ``carry_i = max(0, carry_{i-1} + sent_{i-1} - room_i)`` (Lindley's),
    solved for all columns at once with a cumulative sum and a running minimum. Charge that
    reaches the end of a column is lost (it leaves the array).
    """
    excess = np.maximum(charge_e - full_well_e, 0.0)
    if not excess.any():
        return charge_e
    cols = np.flatnonzero(excess.any(axis=0))
    sub = np.minimum(charge_e[:, cols], full_well_e)
    half = 0.5 * excess[:, cols]
    sub = _spill(sub, half, full_well_e)  # downwards (increasing row)
    sub = _spill(sub[::-1], half[::-1], full_well_e)[::-1]  # upwards
    charge_e[:, cols] = sub
    return charge_e


def _spill(charge: NDArray, sent: NDArray, full_well_e: float) -> NDArray:
    """Charge after ``sent[i]`` leaves pixel i towards i + 1, i + 2, ... filling each to the well."""
    room = full_well_e - charge
    step = np.zeros_like(charge)
    step[1:] = sent[:-1] - room[1:]
    step[0] = -room[0]
    total = np.cumsum(step, axis=0)
    carry = total - np.minimum(np.minimum.accumulate(total, axis=0), 0.0)  # leaving pixel i, w/o sent[i]
    arriving = np.zeros_like(charge)
    arriving[1:] = carry[:-1] + sent[:-1]
    absorbed = arriving - carry
    return np.minimum(charge + np.maximum(absorbed, 0.0), full_well_e)
