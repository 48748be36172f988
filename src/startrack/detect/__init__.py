"""Star detection and centroiding: image -> :class:`startrack.results.Detections`.

Pipeline (DESIGN.md §1; Huffman 2006 §4.1-4.2.2.2, eq. 4.2; Fowler 2013 §II.B-C),
one module per stage::

    prepare      one plane (colour: R + G + B, see .channels); NaN / inf ignored
    smooth       detection image: 2 x 2 mean binning + 3 x 3 binomial kernel (matched filter)
    background   level, noise and clutter of the detection image per 32-px tile, interpolated
    threshold    significance = (image - level) / noise
    label        8-connected regions above 3 sigma that reach 5 sigma (hysteresis)
    deblend      split regions with several separate peaks
    filters      edge, area, peak, elongation, flatness, hot-pixel and clutter rejection
    hot_pixels   where hot pixels are most of the spots: replaced, and the frame detected again
    centroid     weighted sum over the full-resolution pixels of each region (flux, peak,
                 second moments, elongation), then the iteratively windowed Gaussian-weighted
                 centroid about it (the default ``centroid="windowed"``, within a few per cent
                 of the Cramér-Rao bound, see docs/detection.md) with its 1-sigma error

Every stage has alternatives selectable by name (:class:`StarDetector`, whose settings are a
:class:`DetectionSettings`, the object the stages read): dark / median-frame
and row-reference subtraction (:mod:`._dark`), denoising (:mod:`._denoise`), k-sigma, dynamic and
Huffman 2006 pre-filter thresholds (:mod:`._threshold`, :mod:`._prefilters`), 8-connected labelling
or Jacobs 1995 region growing (:mod:`._region_grow`), shape and smear tests (:mod:`._shape`), and six
centroiders (:mod:`._centroiders`); predictive windows (:mod:`._predictive`); the Cramér-Rao
bound (:mod:`._crb`); instrument magnitudes (:mod:`._magnitude`).

``detect(image)`` runs it with the default settings; :class:`StarDetector` holds other
settings. x, y are in our pixel convention (0-based pixel centres, x = column); detections
are sorted brightest (largest flux) first.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._background import low_side_clipped, pixel_noise
    from ._centroiders import CENTROIDERS
    from ._channels import to_single_channel
    from ._compiled import warm_up_detect
    from ._compression import compression_noise_floor
    from ._crb import crb_sigma_px, flux_for_snr, integrated_snr
    from ._dark import median_frame, subtract_dark
    from ._denoise import stack_frames
    from ._details import DetectionDetails
    from ._detector import StarDetector, detect
    from ._filters import clusters_abound, hot_pixel_ok, hot_pixels_abound, peak_fraction, peak_fractions
    from ._fine_pass import MAX_RING_NOISE, fine_significance, quiet_surroundings, ring_noise_ratio, stands_above_ring
    from ._magnitude import calibrate_zero_point, instrument_magnitude
    from ._pipeline import background_model, noise_floor, preprocess
    from ._predictive import WindowDetections
    from ._prefilters import PREFILTER_FORMS, prefilter
    from ._settings import THRESHOLDS, DetectionSettings
    from ._smooth import detection_image
    from ._threshold import significance
    from ._windows import extract_windows

_EXPORTS = _exports_of(__file__)

__all__ = [
    "CENTROIDERS",
    "DetectionDetails",
    "DetectionSettings",
    "MAX_RING_NOISE",
    "StarDetector",
    "THRESHOLDS",
    "WindowDetections",
    "background_model",
    "calibrate_zero_point",
    "clusters_abound",
    "compression_noise_floor",
    "crb_sigma_px",
    "detect",
    "detection_image",
    "extract_windows",
    "fine_significance",
    "flux_for_snr",
    "hot_pixel_ok",
    "hot_pixels_abound",
    "instrument_magnitude",
    "integrated_snr",
    "low_side_clipped",
    "median_frame",
    "noise_floor",
    "peak_fraction",
    "peak_fractions",
    "pixel_noise",
    "preprocess",
    "quiet_surroundings",
    "ring_noise_ratio",
    "significance",
    "stack_frames",
    "stands_above_ring",
    "subtract_dark",
    "to_single_channel",
    "warm_up_detect",
]

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
