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
    centroid     weighted sum over the full-resolution pixels of each region (flux, peak,
                 second moments, elongation), then the iteratively windowed Gaussian-weighted
                 centroid about it (the default ``centroid="windowed"``, within a few per cent
                 of the Cramér-Rao bound, see docs/detection.md) with its 1-sigma error

Every stage has alternatives selectable by name (:class:`StarDetector`): dark / median-frame
and row-reference subtraction (:mod:`.dark`), denoising (:mod:`.denoise`), k-sigma, dynamic and
Huffman 2006 pre-filter thresholds (:mod:`.threshold`, :mod:`.prefilters`), 8-connected labelling
or Jacobs 1995 region growing (:mod:`.region_grow`), shape and smear tests (:mod:`.shape`), and six
centroiders (:mod:`.centroiders`); predictive windows (:mod:`.predictive`); the Cramér-Rao
bound (:mod:`.crb`); instrument magnitudes (:mod:`.magnitude`).

``detect(image)`` runs it with the default settings; :class:`StarDetector` holds other
settings. x, y are in our pixel convention (0-based pixel centres, x = column); detections
are sorted brightest (largest flux) first.
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "to_single_channel": ".channels",
    "crb_sigma_px": ".crb",
    "flux_for_snr": ".crb",
    "integrated_snr": ".crb",
    "median_frame": ".dark",
    "subtract_dark": ".dark",
    "stack_frames": ".denoise",
    "DetectionDetails": ".details",
    "StarDetector": ".detector",
    "detect": ".detector",
    "calibrate_zero_point": ".magnitude",
    "instrument_magnitude": ".magnitude",
    "WindowDetections": ".predictive",
    "low_side_clipped": ".background",
    "pixel_noise": ".background",
    "CENTROIDERS": ".centroiders",
    "THRESHOLDS": ".detector",
    "peak_fraction": ".filters",
    "MAX_RING_NOISE": ".fine_pass",
    "fine_significance": ".fine_pass",
    "quiet_surroundings": ".fine_pass",
    "ring_noise_ratio": ".fine_pass",
    "stands_above_ring": ".fine_pass",
    "background_model": ".pipeline",
    "noise_floor": ".pipeline",
    "preprocess": ".pipeline",
    "detection_image": ".smooth",
    "significance": ".threshold",
    "extract_windows": ".windows",
    "warm_up_detect": ".compiled",
}

__all__ = [
    "CENTROIDERS",
    "DetectionDetails",
    "MAX_RING_NOISE",
    "StarDetector",
    "THRESHOLDS",
    "WindowDetections",
    "background_model",
    "calibrate_zero_point",
    "crb_sigma_px",
    "detect",
    "detection_image",
    "extract_windows",
    "fine_significance",
    "flux_for_snr",
    "instrument_magnitude",
    "integrated_snr",
    "low_side_clipped",
    "median_frame",
    "noise_floor",
    "peak_fraction",
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
