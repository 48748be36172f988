"""Star detection and centroiding: image -> :class:`startrack.results.Detections`.

Pipeline (DESIGN.md §1; seed 000 §4.1-4.2, notes ``seed-000.md`` §1.5-1.9; seed 003 §II.B-C),
one module per stage::

    prepare      one plane (colour: R + G + B, see .channels); NaN / inf ignored
    smooth       detection image: 2 x 2 mean binning + 3 x 3 binomial kernel (matched filter)
    background   level, noise and clutter of the detection image per 32-px tile, interpolated
    threshold    significance = (image - level) / noise
    label        8-connected regions above 3 sigma that reach 5 sigma (hysteresis)
    deblend      split regions with several separate peaks
    filters      edge, area, peak, elongation, flatness, hot-pixel and clutter rejection
    centroid     weighted sum over the full-resolution pixels of each region: x, y, flux,
                 peak, second moments (elongation), 1-sigma centroid error

``detect(image)`` runs it with the default settings; :class:`StarDetector` holds other
settings. x, y are in our pixel convention (0-based pixel centres, x = column); detections
are sorted brightest (largest flux) first.
"""

from __future__ import annotations

from .channels import to_single_channel
from .detector import StarDetector, detect

__all__ = ["StarDetector", "detect", "to_single_channel"]
