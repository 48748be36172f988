"""The spots the detector refused, and why, for the annotated frame and ``rejected.csv``.

The detector ANDs its spot filters and keeps no record of what it dropped
(:func:`startrack.detect._pipeline.spot_filters`). To show them, the same image is detected again
with the same settings but every spot filter off (:data:`RELAXED`); each spot of that run that
is not one of the kept detections (no kept centroid within :data:`SAME_SPOT_PX`) was refused by a
filter, and the first filter it fails, in the detector's order, is given as its reason, from the
spot's own measurements and the filters of :mod:`startrack.detect._filters`: area, elongation,
edge, hot pixel (peak fraction of the 3 x 3 sum; where hot pixels, alone or in pairs and
triples, outnumber the other spots, as the detector judges it, also two to six together: k
pixels' share of the sum to the power 2^(k - 1)), peak SNR. The clutter test needs the local
background model that only the detector sees, so the spots left are detected once more with only
that filter on: those it drops are "clutter". A spot that passes all of those was refused by
packing or the smear-shape test: "another filter (packing or shape)".
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..detect import StarDetector, clusters_abound, hot_pixel_ok, peak_fractions
from ..results import Detections

RELAXED: dict[str, Any] = {"min_area_px": 1, "max_area_px": None, "max_elongation": None, "max_peak_fraction": None,
           "max_clutter": None, "reject_edge": False, "min_peak_snr": 0.0, "min_flatness": 0.0, "min_packing": 0.0,
           "max_stars": None, "smear_px": None, "max_axis_difference_px": None}
SAME_SPOT_PX = 1.5
MAX_REJECTS = 300
"""At most this many refused spots are reported (the brightest)."""
EDGE_PX = 1.5
CATEGORIES = ("area", "elongation", "edge", "hot pixel", "peak SNR", "clutter", "other")


def rejected_spots(image: NDArray, detector: StarDetector, kept: Detections) -> dict[str, list]:
    """Columns ``x, y, area_px, peak, elongation, category, reason`` of the refused spots.

    Parameters
    ----------
    image : ndarray, shape (H, W)
        The pixels the detection ran on.
    detector : StarDetector
        The settings of that detection.
    kept : Detections
        What it kept.

    Returns
    -------
    dict
        Equal-length lists, brightest spot first; ``category`` is one of :data:`CATEGORIES`.
    """
    spots = replace(detector, **RELAXED).detect(image)
    refused = _not_kept(spots, kept)
    fraction = _peak_fraction(image, spots, _judged(detector, spots, refused, image.shape),
                              detector.max_peak_fraction)
    refused = refused[:MAX_REJECTS]
    spots, fraction = spots.take(refused), fraction[refused]
    reasons = [_reason(detector, spots, i, fraction[i], image.shape) for i in range(len(spots))]
    reasons = _clutter(image, detector, spots, reasons)
    out: dict[str, list] = {k: [] for k in ("x", "y", "area_px", "peak", "elongation", "category", "reason")}
    for i, (category, reason) in enumerate(reasons):
        for key, value in (("x", float(spots.x[i])), ("y", float(spots.y[i])), ("area_px", int(spots.area_px[i])),
                           ("peak", float(spots.peak[i])), ("elongation", float(spots.elongation[i])),
                           ("category", category), ("reason", reason)):
            out[key].append(value)
    return out


def without_solved(rejects: dict[str, list], solved: Detections | None) -> dict[str, list]:
    """``rejects`` (:func:`rejected_spots`) without the spots the solve used after all: where the
    detector's spots matched nothing, :func:`startrack.solve_image` solves again on those found
    with the clutter test off (and the elongation test, on a frame of trails:
    :func:`startrack.solve._second_detection`), and a refused spot of that list (``solved``) is
    then a detection, not a refused one."""
    if solved is None or not rejects["x"]:
        return rejects
    spots = Detections(x=np.asarray(rejects["x"], dtype=float), y=np.asarray(rejects["y"], dtype=float))
    still = _not_kept(spots, solved)
    return {key: [values[i] for i in still] for key, values in rejects.items()}


def _clutter(image: NDArray, cfg: StarDetector, spots: Detections,
             reasons: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """Mark as "clutter" the unexplained spots that a detection with only the clutter test drops."""
    other = [i for i, (category, _) in enumerate(reasons) if category == "other"]
    if not other or cfg.max_clutter is None:
        return reasons
    survivors = replace(cfg, **{**RELAXED, "max_clutter": cfg.max_clutter}).detect(image)
    dropped = set(_not_kept(spots.take(np.asarray(other)), survivors).tolist())
    out = list(reasons)
    for k, i in enumerate(other):
        if k in dropped:
            out[i] = ("clutter", f"cluttered background (clutter ratio > max_clutter {cfg.max_clutter:g})")
    return out


def _not_kept(spots: Detections, kept: Detections) -> NDArray[np.int64]:
    """Indices of ``spots`` with no kept detection within :data:`SAME_SPOT_PX`."""
    if len(spots) == 0:
        return np.zeros(0, dtype=np.int64)
    if len(kept) == 0:
        return np.arange(len(spots))
    dx = spots.x[:, None] - kept.x[None, :]
    dy = spots.y[:, None] - kept.y[None, :]
    nearest = np.min(dx * dx + dy * dy, axis=1)
    return np.flatnonzero(nearest > SAME_SPOT_PX**2)


def _judged(cfg: StarDetector, spots: Detections, refused: NDArray[np.int64],
            shape: tuple[int, int]) -> NDArray[np.bool_]:
    """The spots (N,) the detector's hot-pixel tests judge: the kept ones (all but ``refused``)
    and the refused ones that no filter before the hot-pixel tests, nor the peak SNR, refuses."""
    judged = np.ones(len(spots), dtype=bool)
    for i in refused:
        judged[i] = _reason(cfg, spots, int(i), 0.0, shape)[0] == "other"
    return judged


def _peak_fraction(image: NDArray, spots: Detections, judged: NDArray[np.bool_],
                   limit: float | None) -> NDArray[np.float64]:
    """The hot-pixel test's measure of every spot (N,) at the pixel nearest its centroid: the
    peak over the 3 x 3 sum, or with clusters of two to six where hot pixels abound, as the
    detector decides (:func:`startrack.detect.clusters_abound`, the pairs and triples counted
    among the spots it ``judged``, :func:`_judged`)."""
    h, w = image.shape
    px = np.clip(np.rint(spots.x).astype(np.int64), 0, w - 1)
    py = np.clip(np.rint(spots.y).astype(np.int64), 0, h - 1)
    measures = peak_fractions(image, spots.background, px, py, noise=spots.noise)
    hot = ~hot_pixel_ok(measures.single, limit)
    return measures.block if clusters_abound(hot, measures.cluster, judged & ~hot, limit) else measures.single


def _reason(cfg: StarDetector, spots: Detections, i: int, fraction: float, shape: tuple[int, int]) -> tuple[str, str]:
    area, elong = int(spots.area_px[i]), float(spots.elongation[i])
    x, y = float(spots.x[i]), float(spots.y[i])
    h, w = shape
    if area < cfg.min_area_px:
        return "area", f"area {area} px < min_area_px {cfg.min_area_px}"
    if cfg.max_area_px is not None and area > cfg.max_area_px:
        return "area", f"area {area} px > max_area_px {cfg.max_area_px}"
    if cfg.max_elongation is not None and elong > cfg.max_elongation:
        return "elongation", f"elongation {elong:.1f} > max_elongation {cfg.max_elongation:g}"
    if cfg.reject_edge and (x < EDGE_PX or y < EDGE_PX or x > w - 1 - EDGE_PX or y > h - 1 - EDGE_PX):
        return "edge", "touches the image edge"
    if cfg.max_peak_fraction is not None and not (0 <= fraction <= cfg.max_peak_fraction):
        return "hot pixel", (f"hot pixel (or two to six together): {fraction:.2f} of its 3 x 3 sum "
                             f"(> {cfg.max_peak_fraction:g})")
    snr = float(spots.peak[i]) / spots.noise if spots.noise > 0 else np.inf
    if snr < cfg.min_peak_snr:
        return "peak SNR", f"peak SNR {snr:.1f} < min_peak_snr {cfg.min_peak_snr:g}"
    return "other", "another filter (packing or shape)"
