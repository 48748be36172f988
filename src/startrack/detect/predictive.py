"""Predictive (windowed) centroiding: measure only small windows around predicted positions.

Seed 004 (Samaan, Mortari, Pollock & Junkins 2002; notes ``seed-001-004.md`` §2.2 step 4) and
seed 000 §4.2.3 (notes §1.11): in tracking, the attitude and rate predict where each catalogue
star will fall; a mask centred on each prediction is centroided, and the rest of the frame is
never read. A small prediction error only moves where the window starts.

Per window (all windows at once, as one (N, S, S) stack):

1. background = median of the window's outer ring of pixels, noise = 1.4826 x their median
   absolute deviation (a star in the window does not reach its ring when the window is a few
   PSF widths wide);
2. found when the brightest 3 x 3 mean of the window, above the background, exceeds the
   detector's ``sigma`` times the 3 x 3 mean's noise (noise / 3), the same matched-filter test
   as the full-frame detection;
3. the detector's centroider: the window methods (``windowed``, ``mle``) on the window, the
   region methods on the window's pixels above ``grow_sigma`` times the noise.

The window's half-width follows the rule of the notes (§2.2): ``ceil(3 s) + smear / 2 +
prediction margin``; the caller passes it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..io.channels import to_single_channel
from ..results import Detections
from .centroid import measure_spots, sigma_eq42
from .centroid_mle import mle_centroid
from .centroid_windowed import windowed_centroid
from .centroiders import WINDOW_METHODS, CentroidInputs, estimate_psf_sigma, run_centroider
from .label import Regions
from .windows import Windows

if TYPE_CHECKING:
    from .detector import StarDetector

MAD_TO_SIGMA = 1.4826


@dataclass(frozen=True)
class WindowDetections:
    """The stars found in predicted windows.

    Attributes
    ----------
    detections : Detections
        Brightest first; ``background`` and ``noise`` are the medians over the windows.
    window_index : ndarray of int, shape (N,)
        Which prediction (index into the input x, y) each detection was found in.
    """

    detections: Detections = field(default_factory=Detections)
    window_index: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))

    def __len__(self) -> int:
        return len(self.detections)


def cut_windows(image: NDArray, x: NDArray, y: NDArray, half: int, channel) -> Windows:
    """Windows of the raw image (colour reduced window by window, non-finite -> NaN)."""
    array = np.asarray(image)
    if array.ndim not in (2, 3) or min(array.shape[:2]) < 2:
        raise InvalidInputError(f"image must be (H, W) or (H, W, C), got shape {array.shape}")
    if not (np.issubdtype(array.dtype, np.integer) or np.issubdtype(array.dtype, np.floating)):
        raise InvalidInputError(f"image must hold integers or floats, got dtype {array.dtype}")
    h, w = array.shape[:2]
    cx, cy = np.rint(x).astype(np.int64), np.rint(y).astype(np.int64)
    k = np.arange(-half, half + 1)
    rows, cols = cy[:, None] + k, cx[:, None] + k
    inside = ((rows >= 0) & (rows < h))[:, :, None] & ((cols >= 0) & (cols < w))[:, None, :]
    values = array[np.clip(rows, 0, h - 1)[:, :, None], np.clip(cols, 0, w - 1)[:, None, :]]
    if values.ndim == 4:
        n, s = values.shape[:2]
        values = to_single_channel(values.reshape(n * s, s, -1), channel).reshape(n, s, s)
    values = values.astype(np.float64)
    values[~(inside & np.isfinite(values))] = np.nan
    return Windows(values, cx - half, cy - half)


def ring_statistics(windows: Windows) -> tuple[NDArray, NDArray]:
    """Median and robust standard deviation of each window's outer ring, shape (N,) each."""
    ring = windows.border()
    if np.isnan(ring).any():
        level = np.nanmedian(ring, axis=1)
        mad = np.nanmedian(np.abs(ring - level[:, None]), axis=1)
    else:
        level = np.median(ring, axis=1)
        mad = np.median(np.abs(ring - level[:, None]), axis=1)
    return np.nan_to_num(level), np.nan_to_num(MAD_TO_SIGMA * mad)


def _box3_peak(signal: NDArray) -> NDArray:
    """Largest 3 x 3 mean of each window (NaN as 0), shape (N,)."""
    s = np.nan_to_num(signal)
    rows = s[:, :-2] + s[:, 1:-1] + s[:, 2:]
    box = rows[:, :, :-2] + rows[:, :, 1:-1] + rows[:, :, 2:]
    return box.reshape(len(s), -1).max(axis=1) / 9.0


def _window_regions(signal: NDArray, windows: Windows, threshold: NDArray) -> Regions:
    """The pixels above ``threshold`` (N,) of each window, as Regions."""
    above = np.nan_to_num(signal, nan=-np.inf) > threshold[:, None, None]
    index, j, i = np.nonzero(above)
    counts = np.bincount(index, minlength=len(windows))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    return Regions(index.astype(np.int64), (windows.y0[index] + j).astype(np.int64),
                   (windows.x0[index] + i).astype(np.int64), starts)


def measure_windows(cfg: StarDetector, image: NDArray, x: NDArray, y: NDArray, half: int
                    ) -> WindowDetections:
    """Find and centroid stars in windows of half-width ``half`` around (x, y) (module
    docstring); see :meth:`StarDetector.measure_windows`."""
    windows = cut_windows(image, x, y, half, cfg.channel)
    if cfg.dark_frame is not None:
        dark = cut_windows(cfg.dark_frame, x, y, half, cfg.channel).values
        windows = Windows(windows.values - dark, windows.x0, windows.y0)
    level, noise = ring_statistics(windows)
    noise = np.maximum(noise, 1e-6 * np.nanmax(np.abs(windows.values), axis=(1, 2)) + 1e-12)
    signal = windows.values - level[:, None, None]
    found = _box3_peak(signal) > cfg.sigma * noise / 3.0
    if not found.any():
        return WindowDetections(Detections(background=float(np.median(level)),
                                           noise=float(np.median(noise))))
    index = np.flatnonzero(found)
    sub = Windows(windows.values[index], windows.x0[index], windows.y0[index])
    return _centroid_windows(cfg, sub, signal[index], level[index], noise[index], index)


def _centroid_windows(cfg: StarDetector, windows: Windows, signal: NDArray, level: NDArray,
                      noise: NDArray, index: NDArray) -> WindowDetections:
    regions = _window_regions(signal, windows, cfg.grow_sigma * noise)
    has = regions.counts > 0
    windows, signal, level, noise, index = (windows.take(has), signal[has], level[has],
                                            noise[has], index[has])
    regions = regions.select(has)
    spots = measure_spots(regions, signal[regions.index, regions.y - windows.y0[regions.index],
                                         regions.x - windows.x0[regions.index]])
    result = _run(cfg, windows, regions, spots, level, noise)
    ok = result.ok
    x, y = np.where(ok, result.x, spots.x), np.where(ok, result.y, spots.y)
    flux = np.where(ok & np.isfinite(result.flux), result.flux, spots.flux)
    sigma = sigma_eq42(spots.peak / noise) if cfg.uncertainty == "eq4.2" else result.sigma_px
    order = np.argsort(-flux, kind="stable")
    det = Detections(x=x[order], y=y[order], flux=flux[order], sigma_px=sigma[order],
                     area_px=spots.area_px.astype(np.int64)[order], peak=spots.peak[order],
                     elongation=spots.elongation[order], background=float(np.median(level)),
                     noise=float(np.median(noise)))
    return WindowDetections(det, index[order].astype(np.int64))


def _run(cfg: StarDetector, windows: Windows, regions: Regions, spots, level, noise):
    """The configured centroider on windows (window methods) or their regions."""
    if cfg.centroid not in WINDOW_METHODS:
        inputs = CentroidInputs(np.zeros((1, 1)), None, regions, spots, _raw(windows, regions),
                                level, noise)
        return run_centroider(cfg.centroid, inputs)
    sigma = estimate_psf_sigma(spots) if cfg.psf_sigma_px is None else cfg.psf_sigma_px
    first = windowed_centroid(windows, level, noise, spots.x, spots.y, sigma,
                              gain_e_per_adu=cfg.gain_e_per_adu)
    if cfg.centroid == "windowed":
        return first
    return mle_centroid(windows, level, noise, np.where(first.ok, first.x, spots.x),
                        np.where(first.ok, first.y, spots.y), spots.flux, sigma,
                        fit_sigma=cfg.psf_sigma_px is None, gain_e_per_adu=cfg.gain_e_per_adu)


def _raw(windows: Windows, regions: Regions) -> NDArray[np.float64]:
    """Raw window values of the region pixels, shape (M,)."""
    return windows.values[regions.index, regions.y - windows.y0[regions.index],
                          regions.x - windows.x0[regions.index]]
