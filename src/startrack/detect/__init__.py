"""Star detection and centroiding: image -> :class:`startrack.results.Detections`.

Pipeline (DESIGN.md §1; seed 000 §4.1-4.2, notes ``seed-000.md`` §1.5-1.9; seed 003 §II.B-C)::

    prepare      one float32 plane (colour: R + G + B), NaN / inf marked and ignored
    smooth       detection image: 2 x 2 mean binning + 3 x 3 box mean (a matched filter)
    background   level and noise of the detection image, per 64-px tile, interpolated
    threshold    significance = (image - level) / noise; candidates above 5 sigma
    label        8-connected regions, grown down to 3 sigma (hysteresis)
    filters      edge, area, peak, elongation, flatness and hot-pixel rejection
    centroid     weighted sum over the full-resolution pixels of each region, flux, peak,
                 second moments (elongation), 1-sigma centroid error

``detect(image)`` runs it with the default settings; :class:`StarDetector` holds other
settings. x, y are in our pixel convention (0-based pixel centres, x = column).
"""

from __future__ import annotations

from .channels import to_single_channel
from .detector import StarDetector, detect

__all__ = ["StarDetector", "detect", "to_single_channel"]
