"""Large frames in horizontal strips, so that the detector's memory stays bounded.

A frame of more than ``max_block_px`` pixels is cut into strips of whole rows, each of at most
about ``max_block_px`` pixels including an overlap of :data:`MARGIN_PX` rows on either side;
each strip runs through the whole pipeline on a view of the input (no copy of the frame), and a
detection is kept by the strip whose own rows (without the overlap) contain its centroid. Strip
boundaries fall on multiples of the background tile, so the tiles are the ones a single pass
would use. The working memory is that of one strip, whatever the frame's size (measured with
``tracemalloc`` by ``benchmarks/detect_speed.py --huge``): float input is copied to float32
strip by strip, and the input itself is the caller's and is never copied whole.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..results import Detections
from ._details import PER_DETECTION, DetectionDetails
from ._merge import brightest_first
from ._pipeline import detect_frame
from ._settings import DetectionSettings

MARGIN_PX = 64
"""Rows shared by neighbouring strips: more than the largest spot's half-height."""


def strip_rows(height: int, width: int, max_block_px: int, tile_px: int) -> list[tuple[int, int]]:
    """Own row ranges [start, stop) of the strips covering ``height`` rows."""
    rows = max(tile_px, (max_block_px // max(width, 1) - 2 * MARGIN_PX) // tile_px * tile_px)
    rows = max(rows, 2 * MARGIN_PX)
    return [(start, min(height, start + rows)) for start in range(0, height, rows)]


def detect_in_strips(cfg: DetectionSettings, image: NDArray) -> DetectionDetails:
    """Detect strip by strip and merge (module docstring)."""
    h, w = image.shape[:2]
    parts, levels, noises, k_sigmas = [], [], [], []
    for start, stop in strip_rows(h, w, cfg.max_block_px, cfg.tile_px):
        lo, hi = max(0, start - MARGIN_PX), min(h, stop + MARGIN_PX)
        dark = None if cfg.dark_frame is None else np.asarray(cfg.dark_frame)[lo:hi]
        part = detect_frame(cfg, image[lo:hi], dark)
        levels.append(part.detections.background)
        noises.append(part.detections.noise)
        k_sigmas.append(part.k_sigma)
        y = part.detections.y + lo
        own = (y >= start - 0.5) & (y < stop - 0.5)
        parts.append((part.take(own), lo))
    return _merge(cfg, parts, w, h, float(np.median(levels)), float(np.median(noises)),
                  float(np.median(k_sigmas)))


def _merge(cfg: DetectionSettings, parts: list[tuple[DetectionDetails, int]], width: int, height: int,
           level: float, noise: float, k_sigma: float) -> DetectionDetails:
    """Concatenate the strips' detections (y shifted to the frame), merge the ones two strips
    both kept (:mod:`._merge`), brightest first."""
    def cat(name: str, source: str = "detections") -> NDArray:
        arrays = [getattr(getattr(p, source) if source else p, name) for p, _ in parts]
        return np.concatenate(arrays)
    dets = {name: cat(name) for name in ("x", "flux", "sigma_px", "area_px", "peak",
                                           "elongation", "point_quality")}
    dets["y"] = np.concatenate([p.detections.y + lo for p, lo in parts])
    detections = Detections(**dets, background=level, noise=noise, width=width, height=height)
    extra = {name: cat(name, "") for name in PER_DETECTION}
    details = DetectionDetails(detections=detections, **extra, k_sigma=k_sigma, centroid=cfg.centroid)
    return brightest_first(details, cfg.max_stars)
