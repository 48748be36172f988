"""The detection pipeline of one frame, stage by stage, for the settings of a
:class:`.DetectionSettings` (the :class:`.StarDetector` facade passes itself).

prepare (+ dark, row reference, denoise) -> detection image -> background -> threshold and
grouping -> deblend, edge -> spot measurements and filters -> centroid -> Detections.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import require
from ..results import Detections
from . import _filters as filters
from ._background import (
    BackgroundModel,
    global_background,
    low_side_clipped,
    pixel_noise,
    tiled_background,
    with_clutter_floor,
    with_noise_floor,
)
from ._centroid import SpotMeasurements, centroid_sigma, measure_spots, sigma_eq42, take_spots
from ._centroiders import CentroidInputs, run_centroider
from ._compression import crowded
from ._dark import subtract_dark, subtract_row_reference
from ._deblend import split_regions
from ._denoise import anisotropic_diffusion, gaussian_smooth
from ._details import DetectionDetails
from ._filters import HotMeasures
from ._fine_pass import (
    BLEND_RING_PX,
    MAX_BLEND_RING_NOISE,
    add_new_regions,
    fine_regions,
    fine_significance,
    quiet_surroundings,
    ring_noise_ratio,
    touches,
)
from ._hot_pixels import hot_pixels_dominate, without_hot_pixels
from ._label import Regions, label_regions
from ._magnitude import instrument_magnitude
from ._merge import brightest_first
from ._point_source import CoreShape, core_shape, frame_top, point_quality, saturated_spots
from ._prefilters import packing, prefilter
from ._prepare import PreparedImage, prepare_image
from ._region_grow import grow_regions
from ._settings import DetectionSettings
from ._shape import smear_ok, spot_shape
from ._smooth import detection_image
from ._threshold import significance
from ._windows import fast_median

EDGE_MARGIN_PX = 2
"""A spot whose peak is closer than this to the border (full-resolution px) is cut off."""

SHARP_CORE_PX, SHARP_MIN_SNR = 1.3, 10.0
"""The fine pass runs on frames whose significant point sources (peak over pixel noise at least
10) have a median half-maximum size (Gaussian-equivalent sd) under 1.3 px: small JPEGs and the
openstartracker frames (0.5-1.0 px), not stars of 1.5 px sd that the binned image matches."""

EDGE_CORE_PX = 64
"""... and so is one whose core (above the threshold) touches the border and covers more than
this (full-resolution px): a glow, a limb, a bright star cut in half."""

NOISE_FLOOR_FRACTION = 1e-6
"""Noise floor relative to the largest absolute value, for noise-free (simulated) images."""


@dataclass(frozen=True)
class MeasuredRegions:
    """N regions with what the later stages read of them, measured once (a subset is taken,
    not measured again: every quantity is per pixel or per region).

    Attributes
    ----------
    regions : Regions
        Full-resolution pixels of the N spots.
    raw, signal : ndarray, shape (M,)
        Each pixel's value (float64, NaN where missing) and its value less the background
        level (0 where missing).
    spots : SpotMeasurements
        The weighted-sum measurements, shape (N,) each.
    peak_level, local_noise : ndarray, shape (N,)
        Background level and pixel noise at each spot's peak.
    hot_tests : HotMeasures or None
        The spots' hot-pixel measures (:func:`._filters.peak_fractions`) when measured already
        (:func:`with_hot_tests`); the filters measure them otherwise.
    """

    regions: Regions
    raw: NDArray[np.float64]
    signal: NDArray[np.float64]
    spots: SpotMeasurements
    peak_level: NDArray[np.float64]
    local_noise: NDArray[np.float64]
    hot_tests: HotMeasures | None = None

    def __len__(self) -> int:
        return len(self.regions)

    def take(self, keep: NDArray[np.bool_]) -> MeasuredRegions:
        """The regions where ``keep`` (shape (N,)) is True, renumbered as :meth:`Regions.select`
        (``self`` when it keeps them all)."""
        if keep.all():
            return self
        pixels = keep[self.regions.index]
        tests = None if self.hot_tests is None else HotMeasures(*(m[keep] for m in self.hot_tests))
        return MeasuredRegions(self.regions.select(keep), self.raw[pixels], self.signal[pixels],
                               take_spots(self.spots, keep), self.peak_level[keep], self.local_noise[keep], tests)


@dataclass(frozen=True)
class Frame:
    """A prepared frame with its background: what every later stage reads."""

    prepared: PreparedImage
    model: BackgroundModel
    skewed: bool
    noise_px: float
    binning: int
    x_offset: int
    det_snr: NDArray[np.float32] | None = None
    """The detection image's significance when it was computed already for this model (a JPEG's
    crowd test, :func:`with_compression_floor`), else None."""

    @functools.cached_property
    def top(self) -> float:
        """The prepared plane's largest value (:func:`.point_source.frame_top`): the level of a
        saturated (clipped) star's core."""
        return frame_top(self.prepared.data)


def detect_frame(cfg: DetectionSettings, image: NDArray, dark: NDArray | None) -> DetectionDetails:
    """Run the whole pipeline on one frame (or one strip of a large frame); a second time with
    the hot pixels replaced where they are most of the first pass's spots (:mod:`._hot_pixels`)."""
    prepared, x_offset = preprocess(cfg, image, dark)
    skewed = low_side_clipped(np.asarray(image))  # the raw frame: a dark frame shifts the zero
    frame, det = frame_of(cfg, prepared, skewed, x_offset)
    if frame.model.noise <= 0:  # a constant image
        return empty_details(frame, image.shape[1], cfg)
    regions, k_sigma = find_regions(cfg, frame, det)
    found = with_hot_tests(frame, measure_regions(frame, regions))
    if hot_pixels_dominate(require(found.hot_tests, "the hot-pixel tests"), cfg.max_peak_fraction):
        frame, det = frame_of(cfg, with_hot_pixels_replaced(cfg, frame), skewed, x_offset)
        regions, k_sigma = find_regions(cfg, frame, det)
        found = measure_regions(frame, regions)
    kept = with_fine_pass(cfg, frame, filter_spots(cfg, frame, found), regions, k_sigma)
    if len(kept) == 0:
        return empty_details(frame, image.shape[1], cfg, k_sigma)
    return measure(cfg, frame, kept, k_sigma, image.shape[1])


def frame_of(cfg: DetectionSettings, prepared: PreparedImage, skewed: bool, x_offset: int
             ) -> tuple[Frame, NDArray[np.float32]]:
    """The frame of a prepared plane (its background model and pixel noise) and its detection
    image; ``skewed``: the raw frame's low side is clipped."""
    binning = min(cfg.binning, *prepared.data.shape)
    det = detection_image(prepared.data, binning, cfg.kernel, cfg.kernel_px, prepared.invalid)
    model, snr = background_model(cfg, det, binning, skewed), None
    if cfg.compression_noise > 0:
        model, snr = with_compression_floor(cfg, det, model, binning)
    noise_px = pixel_noise(prepared.data, model) or noise_floor(prepared.data, model.level)
    return Frame(prepared, model, skewed, noise_px, binning, x_offset, snr), det


def with_hot_pixels_replaced(cfg: DetectionSettings, frame: Frame) -> PreparedImage:
    """The frame's plane with its hot pixels replaced (:func:`.hot_pixels.without_hot_pixels`,
    against the interpolated background level and the pixel noise)."""
    data = frame.prepared.data
    level = frame.model.maps(np.arange(data.shape[0]), np.arange(data.shape[1]))[0]
    level = np.broadcast_to(np.asarray(level, dtype=np.float32), data.shape)  # a constant model's is a float
    cleaned = without_hot_pixels(data, level, frame.noise_px, require(cfg.max_peak_fraction, "max_peak_fraction"))
    return PreparedImage(cleaned, frame.prepared.invalid)


def preprocess(cfg: DetectionSettings, image: NDArray, dark: NDArray | None
               ) -> tuple[PreparedImage, int]:
    """Check and reduce the image, subtract the dark frame and the row reference, denoise.
    Returns the prepared plane and the number of leading columns cut off."""
    prepared = prepare_image(image, cfg.channel)
    data, x_offset = prepared.data, 0
    if dark is not None:
        data = subtract_dark(data, dark)
    if sum(cfg.dark_columns):
        data = subtract_row_reference(data, *cfg.dark_columns)
        x_offset = cfg.dark_columns[0]
    if cfg.denoise == "gaussian":
        data = gaussian_smooth(data, cfg.denoise_sigma_px)
    elif cfg.denoise == "diffusion":
        noise = global_background(np.asarray(data, dtype=np.float32)).noise or 1.0
        data = anisotropic_diffusion(data, cfg.diffusion_iterations,
                                     cfg.diffusion_kappa_sigma * noise)
    if data is prepared.data:
        return prepared, x_offset
    invalid = prepared.invalid
    if invalid is not None and x_offset:
        invalid = invalid[:, x_offset: x_offset + data.shape[1]]
    return PreparedImage(data, invalid), x_offset


def background_model(cfg: DetectionSettings, det: NDArray, binning: int, skewed: bool = False) -> BackgroundModel:
    """Background of the detection image, tile centres in full-resolution pixels; ``skewed``:
    the frame's low side is clipped (:func:`.background.low_side_clipped`)."""
    if cfg.background == "global":
        model = global_background(det)
    else:
        tile = max(1, cfg.tile_px // binning)
        model = tiled_background(det, tile, scale=binning, offset=(binning - 1) / 2, skewed=skewed)
    return with_noise_floor(model, noise_floor(det, model.level)) if model.noise <= 0 else model


def with_compression_floor(cfg: DetectionSettings, det: NDArray, model: BackgroundModel, binning: int
                           ) -> tuple[BackgroundModel, NDArray[np.float32] | None]:
    """A JPEG's floor (``cfg.compression_noise``, :mod:`.compression`): on the clutter filter's
    clean sky always, on the noise where the unfloored threshold finds a crowd of spots. Returns
    the model and the detection image's significance under it (None when the noise changed:
    :func:`find_regions` computes it again)."""
    floor = cfg.compression_noise
    snr = significance(det, model, binning)
    if crowded(snr, cfg.sigma):
        return with_clutter_floor(with_noise_floor(model, floor), floor), None
    return with_clutter_floor(model, floor), snr


def noise_floor(values: NDArray, level: float) -> float:
    """Noise floor for a noise-free (simulated) image: a millionth of the largest deviation
    from the background (0 when the image is constant)."""
    largest = float(np.fmax.reduce(np.abs(values - np.float32(level)), axis=None))  # NaN-free
    return NOISE_FLOOR_FRACTION * largest if np.isfinite(largest) else 0.0


# --- threshold and grouping -------------------------------------------------------------------

def group(cfg: DetectionSettings, mask: NDArray[np.bool_], jump: int) -> Regions:
    """8-connected labelling, or Jacobs 1995's region growing from a jump grid."""
    return grow_regions(mask, jump) if cfg.grouping == "region-grow" else label_regions(mask)


def find_regions(cfg: DetectionSettings, frame: Frame, det: NDArray) -> tuple[Regions, float]:
    """Threshold and group by the chosen method; deblend; drop spots at the edge.

    Returns full-resolution regions and the threshold used (noise units).
    """
    if cfg.threshold.startswith("prefilter"):
        return _prefiltered_regions(cfg, frame), cfg.pixel_sigma
    binning = frame.binning
    snr = significance(det, frame.model, binning) if frame.det_snr is None else frame.det_snr
    regions = group(cfg, snr > min(cfg.grow_sigma, cfg.sigma), max(1, cfg.jump_px // binning))
    peak = regions.max_of(snr) if len(regions) else np.zeros(0)
    k_sigma = dynamic_sigma(peak, cfg) if cfg.threshold == "dynamic" else cfg.sigma
    regions = regions.select(peak > k_sigma) if len(regions) else regions
    if cfg.deblend and len(regions):
        regions = split_regions(regions, snr, k_sigma)
    if cfg.reject_edge and len(regions):
        values = snr[regions.y, regions.x]
        regions = regions.select(filters.peak_away_from_edge(regions, values, det.shape, EDGE_MARGIN_PX // binning,
                                                             values > k_sigma, EDGE_CORE_PX // binning**2))
    return regions.upsample(binning), k_sigma


def with_fine_pass(cfg: DetectionSettings, frame: Frame, kept: MeasuredRegions, found: Regions, k_sigma: float
                   ) -> MeasuredRegions:
    """``kept`` (the binned pass's spots that passed the filters, out of all it ``found``)
    plus the filtered spots of the full-resolution pass (:mod:`._fine_pass`) that share no pixel
    with any it found, the blends it separates split (with ``deblend``); unchanged when the
    pass is off (no binning, ``fine_sigma`` None, a threshold other than "ksigma": the dynamic
    one targets a count of the binned pass's spots) or not needed (:func:`stars_are_sharp`)."""
    if cfg.fine_sigma is None or frame.binning == 1 or cfg.threshold != "ksigma" or \
            not stars_are_sharp(frame, kept):
        return kept
    data, regions = frame.prepared.data, kept.regions
    fine_sigma = max(cfg.fine_sigma, k_sigma)
    snr = fine_significance(data, frame.prepared.invalid, cfg.kernel, cfg.kernel_px, cfg.tile_px, frame.skewed)
    fine = fine_regions(data, frame.prepared.invalid, cfg.kernel, cfg.kernel_px, cfg.tile_px, fine_sigma,
                        cfg.grow_sigma, 1 if cfg.reject_edge else 0, cfg.deblend, frame.skewed, snr=snr)
    base = kept.spots
    unsplit = saturated_spots(regions, kept.raw, frame.top) | (not cfg.deblend)
    unsplit |= ring_noise_ratio(data, base.x, base.y, frame.noise_px, BLEND_RING_PX) > MAX_BLEND_RING_NOISE
    extra = filter_spots(cfg, frame, measure_regions(frame, fine))
    spots = extra.spots
    quiet = quiet_surroundings(data, snr, extra.regions, spots.x, spots.y, frame.noise_px, fine_sigma)
    taken = np.zeros(data.shape, dtype=bool)
    taken[found.y, found.x] = True
    # a saturated star the binned pass left out was cut by the border or rejected for its shape;
    # an extended spot is structure, not the sharp star this pass is for
    quiet &= ~touches(extra.regions, taken) & ~saturated_spots(extra.regions, extra.raw, frame.top)
    quiet &= point_like(frame, kept, extra)
    return measure_regions(frame, add_new_regions(regions, extra.regions, data, unsplit, quiet))


def point_like(frame: Frame, base: MeasuredRegions, extra: MeasuredRegions) -> NDArray[np.bool_]:
    """Shape (K,): which regions of ``extra`` are point sources (:mod:`._point_source`) against
    the frame's reference taken from ``base`` and ``extra`` together."""
    both = [(m.regions, m.signal) for m in (base, extra)]
    shapes = [core_shape(r, signal, r.max(signal)) for r, signal in both]
    shape = CoreShape(*(np.concatenate(measure) for measure in zip(*shapes, strict=True)))
    snr = np.concatenate([r.max(signal) for r, signal in both]) / frame.noise_px
    quality = point_quality(shape, snr, np.zeros(shape.size.size, dtype=bool))
    return quality[len(base):] >= Detections.POINT_SOURCE_MIN_QUALITY


def stars_are_sharp(frame: Frame, kept: MeasuredRegions) -> bool:
    """Whether the frame's significant point sources (peak SNR at least 10, point-source quality
    against the frame's stars, :mod:`.point_source`) have a median half-maximum core
    (:func:`.point_source.core_shape`) under :data:`SHARP_CORE_PX`, or the frame has fewer than
    three such spots to tell: the stars the binned image spreads out and blends. Extended spots
    (lit cloud, glow, leaves) do not vote: two cloud blobs beside two stars would make the median
    theirs."""
    if len(kept) == 0:
        return True
    regions, signal = kept.regions, kept.signal
    peak = regions.max(signal)
    shape = core_shape(regions, signal, peak)
    snr = peak / frame.noise_px
    point = point_quality(shape, snr, np.zeros(snr.size, dtype=bool)) >= Detections.POINT_SOURCE_MIN_QUALITY
    significant = np.isfinite(shape.size) & (snr >= SHARP_MIN_SNR) & point
    return significant.sum() < 3 or float(fast_median(shape.size[significant])) < SHARP_CORE_PX  # finite sizes


def dynamic_sigma(peak_snr: NDArray, cfg: DetectionSettings) -> float:
    """Huffman 2006 §8.2.3's dynamic threshold for one frame: the lowest k in [sigma, max_sigma]
    that leaves at most ``target_stars`` spots (by their peak significance)."""
    if peak_snr.size <= cfg.target_stars:
        return float(cfg.sigma)
    kth = float(np.sort(peak_snr)[::-1][cfg.target_stars])  # the first spot left out
    return float(min(max(cfg.sigma, kth), cfg.max_sigma))


def _prefiltered_regions(cfg: DetectionSettings, frame: Frame) -> Regions:
    """Huffman 2006's single-pixel threshold + 5 x 5 pre-filter (window or grid), at full
    resolution, then grouping and the edge filter."""
    data = frame.prepared.data
    h, w = data.shape
    level, noise = frame.model.maps(np.arange(h), np.arange(w))
    scale = frame.noise_px / frame.model.noise
    with np.errstate(invalid="ignore"):
        mask = (data - level) > cfg.pixel_sigma * scale * np.asarray(noise)
    mask = prefilter(mask, cfg.threshold.removeprefix("prefilter-"), cfg.prefilter_count)
    regions = group(cfg, mask, cfg.jump_px)
    if cfg.reject_edge and len(regions):
        regions = regions.select(filters.away_from_edge(regions, data.shape))
    return regions


# --- measurement, filters, centroid ------------------------------------------------------------

def measure_regions(frame: Frame, regions: Regions) -> MeasuredRegions:
    """Each pixel's raw value and background-subtracted signal (0 where invalid), the spots'
    weighted-sum measurements, and the background level and pixel noise at their peaks."""
    data, invalid, model = frame.prepared.data, frame.prepared.invalid, frame.model
    raw = data[regions.y, regions.x].astype(np.float64)
    signal = raw - model.level_at(regions.x, regions.y)
    if invalid is not None:
        signal[invalid[regions.y, regions.x]] = 0.0
    spots = measure_spots(regions, signal)
    peak_level, peak_noise = model.at(spots.peak_x, spots.peak_y)
    return MeasuredRegions(regions, raw, signal, spots, peak_level, frame.noise_px * peak_noise / model.noise)


def hot_measures(frame: Frame, found: MeasuredRegions) -> HotMeasures:
    """The spots' hot-pixel measures (:func:`._filters.peak_fractions`): those ``found``
    carries, else measured."""
    if found.hot_tests is not None:
        return found.hot_tests
    spots = found.spots
    return filters.peak_fractions(frame.prepared.data, found.peak_level, spots.peak_x, spots.peak_y,
                                  noise=found.local_noise)


def with_hot_tests(frame: Frame, found: MeasuredRegions) -> MeasuredRegions:
    """``found`` carrying its spots' hot-pixel measures (:func:`hot_measures`)."""
    return replace(found, hot_tests=hot_measures(frame, found))


def filter_spots(cfg: DetectionSettings, frame: Frame, found: MeasuredRegions) -> MeasuredRegions:
    """The regions that pass every spot filter (:func:`spot_filters`)."""
    if len(found) == 0:
        return found
    return found.take(spot_filters(cfg, frame, found))


def measure(cfg: DetectionSettings, frame: Frame, kept: MeasuredRegions, k_sigma: float,
            full_width: int) -> DetectionDetails:
    """Centroid the (filtered) spots and pack the result."""
    saturated = saturated_spots(kept.regions, kept.raw, frame.top)
    with np.errstate(invalid="ignore", divide="ignore"):
        peak_snr = kept.spots.peak / kept.local_noise
        quality = point_quality_of(kept, saturated, peak_snr)
    inputs = CentroidInputs(frame.prepared.data, frame.prepared.invalid, kept.regions, kept.spots, kept.raw,
                            kept.peak_level, kept.local_noise, saturated,
                            quality < Detections.POINT_SOURCE_MIN_QUALITY)
    return pack(cfg, frame, inputs, k_sigma, full_width, quality, peak_snr)


def spot_filters(cfg: DetectionSettings, frame: Frame, found: MeasuredRegions) -> NDArray[np.bool_]:
    """The AND of all spot filters on the measured regions (see :mod:`._filters`,
    :mod:`._prefilters`, :mod:`._shape`; the hot-pixel measures by :func:`hot_measures`)."""
    regions, spots, local_noise = found.regions, found.spots, found.local_noise
    fraction, clusters, blocks = hot_measures(frame, found)
    keep = np.isfinite(spots.x) & (spots.flux > 0)
    keep &= filters.area_ok(spots.area_px, cfg.min_area_px, cfg.max_area_px)
    keep &= filters.peak_ok(spots.peak / local_noise, cfg.min_peak_snr)
    keep &= filters.elongation_ok(spots.elongation, cfg.max_elongation)
    keep &= filters.flatness_ok(spots.flatness, cfg.min_flatness)
    hot = ~filters.hot_pixel_ok(fraction, cfg.max_peak_fraction)
    keep &= ~hot
    if filters.clusters_abound(hot, clusters, keep, cfg.max_peak_fraction):  # blocks refused, not counted
        keep &= filters.hot_pixel_ok(blocks, cfg.max_peak_fraction)
    keep &= filters.clutter_ok(frame.model.clutter_at(spots.peak_x, spots.peak_y), cfg.max_clutter, keep)
    if cfg.min_packing > 0:
        keep &= packing(regions) >= cfg.min_packing
    if cfg.smear_px is not None or cfg.max_axis_difference_px is not None:
        keep &= smear_ok(spot_shape(regions), cfg.smear_px, cfg.smear_tolerance_px,
                         cfg.max_axis_difference_px, cfg.smear_angle_deg)
    return keep


def pack(cfg: DetectionSettings, frame: Frame, inputs: CentroidInputs, k_sigma: float,
         full_width: int, point_quality: NDArray[np.float64], peak_snr: NDArray[np.float64]) -> DetectionDetails:
    """Centroid with the chosen method (falling back to the weighted sum where it fails), merge
    coincident detections (:mod:`._merge`), sort brightest first, cut to ``max_stars``, and pack
    with the extra measurements (the spots' ``point_quality`` and ``peak_snr``, peak over local
    pixel noise, (N,) each, among them)."""
    spots, noise = inputs.spots, inputs.noise
    result = run_centroider(cfg.centroid, inputs, psf_sigma_px=cfg.psf_sigma_px,
                            half=cfg.window_half_px, gain_e_per_adu=cfg.gain_e_per_adu)
    ok = result.ok & on_frame(frame, result.x, result.y)
    failed = not ok.all()  # else the fallbacks below are not needed
    x, y = np.where(ok, result.x, spots.x), np.where(ok, result.y, spots.y)
    flux = np.where(ok & np.isfinite(result.flux), result.flux, spots.flux)
    # the centroided, and the rest whose weighted sum is a flux on the frame: not a piece of mostly
    # negative signal of a blend the fine pass split
    kept = np.flatnonzero(ok | ((flux > 0) & on_frame(frame, x, y))) if failed else np.arange(len(x))
    if cfg.uncertainty == "eq4.2":
        sigma = sigma_eq42(peak_snr)
    else:  # the centroiders' sigma_px is float64
        sigma = np.where(ok, result.sigma_px, centroid_sigma(spots, noise, "propagated")) if failed else \
            result.sigma_px
    shape = spot_shape(inputs.regions)
    psf = np.where(np.isfinite(result.psf_sigma_px), result.psf_sigma_px, spots.size_px)
    detections = Detections(
        x=x + frame.x_offset, y=y, flux=flux, sigma_px=sigma, area_px=spots.area_px.astype(np.int64),
        peak=spots.peak, elongation=spots.elongation, background=frame.model.level,
        noise=frame.noise_px, width=full_width, height=frame.prepared.data.shape[0],
        point_quality=point_quality)
    details = DetectionDetails(
        detections=detections, mag=instrument_magnitude(flux, cfg.mag_zero_point),
        peak_snr=peak_snr, major_px=shape.major_px, minor_px=shape.minor_px,
        angle_deg=shape.angle_deg, psf_sigma_px=psf, k_sigma=float(k_sigma), centroid=cfg.centroid)
    return brightest_first(details if kept.size == len(x) else details.take(kept), cfg.max_stars)


def on_frame(frame: Frame, x: NDArray, y: NDArray) -> NDArray[np.bool_]:
    """Whether the points (x, y) (shape (N,), prepared-plane pixels) lie on the frame (False for
    NaN)."""
    h, w = frame.prepared.data.shape
    with np.errstate(invalid="ignore"):
        return (np.abs(x - (w - 1) / 2) <= w / 2) & (np.abs(y - (h - 1) / 2) <= h / 2)


def point_quality_of(kept: MeasuredRegions, saturated: NDArray[np.bool_], peak_snr: NDArray) -> NDArray[np.float64]:
    """Point-source quality (:mod:`._point_source`) of the N ``kept`` spots, of which the
    ``saturated`` ones (shape (N,)) are clipped, with their ``peak_snr`` (shape (N,))."""
    regions = kept.regions
    shape = core_shape(regions, kept.raw - kept.peak_level[regions.index], kept.spots.peak)
    return point_quality(shape, peak_snr, saturated)


def empty_details(frame: Frame, full_width: int, cfg: DetectionSettings,
                  k_sigma: float | None = None) -> DetectionDetails:
    """No detection: the frame's background and noise only."""
    detections = Detections(background=frame.model.level, noise=frame.noise_px, width=full_width,
                            height=frame.prepared.data.shape[0], point_quality=np.zeros(0))
    return DetectionDetails(detections=detections,
                            k_sigma=float(cfg.sigma if k_sigma is None else k_sigma),
                            centroid=cfg.centroid)
