"""Predictive (windowed) centroiding: measure only small windows around predicted positions.

Samaan 2002 (Samaan, Mortari, Pollock & Junkins 2002; Samaan 2002 Eq. 1–3 step 4) and
Huffman 2006 §4.2.3: in tracking, the attitude and rate predict where each catalogue
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
   region methods on the window's pixels above ``grow_sigma`` times the noise. The window
   methods' start, flux, peak and shape are those pixels' spot measurements, taken by
   :func:`window_spots` from separable moments of the whole windows (no pixel lists), with the
   separable sums of :mod:`._centroid_windowed`: a few array operations on the whole stack
   instead of a loop over windows (``benchmarks/detect_speed.py`` times the predictive pass).

The window's half-width follows the rule of the Huffman 2006 Table 5.1, §5.1): ``ceil(3 s) + smear / 2 +
prediction margin``; the caller passes it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ..io import to_single_channel
from ..results import Detections
from ._centroid import PIXEL_VARIANCE, SpotMeasurements, axis_ratio, measure_spots, sigma_eq42
from ._centroid_mle import mle_centroid
from ._centroid_windowed import windowed_centroid
from ._centroiders import WINDOW_METHODS, CentroidInputs, estimate_psf_sigma, run_centroider
from ._label import Regions
from ._settings import DetectionSettings
from ._windows import Centroids, Windows, fast_median, separable_moments

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
        return np.nan_to_num(level), np.nan_to_num(MAD_TO_SIGMA * mad)
    level = fast_median(ring)
    return level, MAD_TO_SIGMA * fast_median(np.abs(ring - level[:, None]))


def _box3_peak(signal: NDArray) -> NDArray:
    """Largest 3 x 3 mean of each window (NaN as 0), shape (N,)."""
    s = np.where(np.isnan(signal), 0.0, signal)
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


def window_spots(signal: NDArray, windows: Windows, threshold: NDArray) -> SpotMeasurements:
    """:func:`.centroid.measure_spots` of each window's pixels above ``threshold`` (N,) (the same
    values as on those pixels as Regions, to rounding), from separable moments of the whole
    windows: a few calls on (N, S, S) arrays instead of building pixel lists. Every window must
    have a pixel above a positive threshold."""
    n, size = len(windows), signal.shape[1]
    above = signal > threshold[:, None, None]  # NaN is never above
    s = np.where(above, signal, 0.0)
    k = np.broadcast_to(np.arange(size, dtype=np.float64), (n, size))
    ones = np.ones((n, size))
    m = separable_moments(np.stack([s, s * s, above, s > 0]), ones, k, ones, k)  # (4, N, 3, 3)
    flux, area = m[0, :, 0, 0], m[2, :, 0, 0]
    mx, my = m[0, :, 0, 1] / flux, m[0, :, 1, 0] / flux
    cxx = m[0, :, 0, 2] / flux - mx * mx + PIXEL_VARIANCE
    cyy = m[0, :, 2, 0] / flux - my * my + PIXEL_VARIANCE
    cxy = m[0, :, 1, 1] / flux - mx * my
    p = m[3]
    spread = p[:, 0, 2] + p[:, 2, 0] - 2.0 * (mx * p[:, 0, 1] + my * p[:, 1, 0]) + (mx * mx + my * my) * p[:, 0, 0]
    top = size * size - 1 - s[:, ::-1, ::-1].reshape(n, -1).argmax(axis=1)  # last maximum, as Regions
    peak_y, peak_x = np.divmod(top, size)
    peak = s.reshape(n, -1)[np.arange(n), top]
    return SpotMeasurements(
        x=windows.x0 + mx, y=windows.y0 + my, flux=flux, weight=flux, peak=peak, peak_x=windows.x0 + peak_x,
        peak_y=windows.y0 + peak_y, area_px=np.rint(area).astype(np.int64), elongation=axis_ratio(cxx, cyy, cxy),
        flatness=np.sqrt(np.maximum(m[1, :, 0, 0] / area - (flux / area) ** 2, 0.0)) / peak, spread_px2=spread,
        size_px=np.sqrt(np.maximum(0.5 * (cxx + cyy) - PIXEL_VARIANCE, 0.0)))


def measure_windows(cfg: DetectionSettings, image: NDArray, x: NDArray, y: NDArray, half: int
                    ) -> WindowDetections:
    """Find and centroid stars in windows of half-width ``half`` around (x, y) (module
    docstring); see :meth:`StarDetector.measure_windows`."""
    windows = cut_windows(image, x, y, half, cfg.channel)
    if cfg.dark_frame is not None:
        dark = cut_windows(cfg.dark_frame, x, y, half, cfg.channel).values
        windows = Windows(windows.values - dark, windows.x0, windows.y0)
    level, noise = ring_statistics(windows)
    noise = np.maximum(noise, 1e-6 * np.fmax.reduce(np.abs(windows.values), axis=(1, 2)) + 1e-12)
    signal = windows.values - level[:, None, None]
    found = _box3_peak(signal) > cfg.sigma * noise / 3.0
    found &= (signal > (cfg.grow_sigma * noise)[:, None, None]).any(axis=(1, 2))
    if not found.any():
        return WindowDetections(Detections(background=float(np.median(level)),
                                           noise=float(np.median(noise))))
    if found.all():
        return _centroid_windows(cfg, windows, signal, level, noise, np.arange(len(windows)))
    index = np.flatnonzero(found)
    return _centroid_windows(cfg, windows.take(index), signal[index], level[index], noise[index], index)


def _centroid_windows(cfg: DetectionSettings, windows: Windows, signal: NDArray, level: NDArray,
                      noise: NDArray, index: NDArray) -> WindowDetections:
    """Centroid the windows with a star (each has a pixel above ``grow_sigma`` x noise): the
    window methods straight from the windows (:func:`window_spots` gives their start), the
    region methods on the pixels above that level."""
    threshold = cfg.grow_sigma * noise
    if cfg.centroid in WINDOW_METHODS:
        spots = window_spots(signal, windows, threshold)
        result = _run_window_method(cfg, windows, spots, level, noise)
    else:
        regions = _window_regions(signal, windows, threshold)
        spots = measure_spots(regions, _pixels(signal, windows, regions))
        inputs = CentroidInputs(np.zeros((1, 1)), None, regions, spots,
                                _pixels(windows.values, windows, regions), level, noise)
        result = run_centroider(cfg.centroid, inputs)
    ok = result.ok
    x, y = np.where(ok, result.x, spots.x), np.where(ok, result.y, spots.y)
    flux = np.where(ok & np.isfinite(result.flux), result.flux, spots.flux)
    sigma = sigma_eq42(spots.peak / noise) if cfg.uncertainty == "eq4.2" else result.sigma_px
    order = np.argsort(-flux, kind="stable")
    det = Detections(x=x[order], y=y[order], flux=flux[order], sigma_px=sigma[order],
                     area_px=spots.area_px.astype(np.int64)[order], peak=spots.peak[order],
                     elongation=spots.elongation[order], background=float(fast_median(level)),
                     noise=float(fast_median(noise)))
    return WindowDetections(det, index[order].astype(np.int64))


def _run_window_method(cfg: DetectionSettings, windows: Windows, spots: SpotMeasurements, level: NDArray,
                       noise: NDArray) -> Centroids:
    """The configured window method (``windowed``, or ``mle`` started from it) on the windows."""
    sigma = estimate_psf_sigma(spots) if cfg.psf_sigma_px is None else cfg.psf_sigma_px
    first = windowed_centroid(windows, level, noise, spots.x, spots.y, sigma,
                              gain_e_per_adu=cfg.gain_e_per_adu)
    if cfg.centroid == "windowed":
        return first
    return mle_centroid(windows, level, noise, np.where(first.ok, first.x, spots.x),
                        np.where(first.ok, first.y, spots.y), spots.flux, sigma,
                        fit_sigma=cfg.psf_sigma_px is None, gain_e_per_adu=cfg.gain_e_per_adu)


def _pixels(values: NDArray, windows: Windows, regions: Regions) -> NDArray[np.float64]:
    """``values`` (N, S, S) at the region pixels, shape (M,)."""
    return values[regions.index, regions.y - windows.y0[regions.index], regions.x - windows.x0[regions.index]]
