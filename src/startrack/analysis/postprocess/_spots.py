"""Per-spot tables shared by the analyses: every detection of a set (star or noise) and every
matched star with its catalog magnitude, residual and distance from the principal point.

A detection is a **star** spot when the identification matched it to a catalog star and a
**noise** spot otherwise (Fowler 2013 Ch.6: with every starlight spot labelled, the rest is noise).
The peak fraction is the spot's brightest pixel over its volume (flux): 1 for a single hot
pixel, small for a wide or flat spot. It stands in for Fowler 2013's flatness factor (std / max of
the spot's pixels), which needs the spot's pixels the detector does not keep.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ...catalog import load_catalog
from ...errors import require
from ...results import AttitudeSolution
from .._records import ImageRecord
from ._core import ResultSet


def matched_mask(solution: AttitudeSolution) -> NDArray[np.bool_]:
    """True for each detection (N,) that the solution matched to a catalog star."""
    n = 0 if solution.detections is None else len(solution.detections)
    mask = np.zeros(n, dtype=bool)
    if solution.solved:
        mask[solution.matches.det_index] = True
    return mask


def principal_point(record: ImageRecord) -> tuple[float, float]:
    """The solution camera's principal point (px); the image centre when there is no camera."""
    camera = record.solution.camera or record.camera
    if camera is not None:
        return float(camera.cx), float(camera.cy)
    det = record.solution.detections
    if det is not None:
        height, width = det.height, det.width
    else:
        height, width = np.shape(require(record.image, "the record's image"))[:2]
    return (width - 1) / 2.0, (height - 1) / 2.0


def detection_table(result_sets: Sequence[ResultSet]) -> dict[str, NDArray]:
    """One row per detection of every record: set, record, index, star (matched or not), x, y
    (px), flux (volume, counts), area_px, peak (counts), peak_fraction, elongation, radius_px."""
    rows: dict[str, list] = {k: [] for k in ("set", "record", "index", "star", "x", "y", "flux", "area_px",
                                              "peak", "peak_fraction", "elongation", "radius_px")}
    for s in result_sets:
        for record in s.records:
            det = record.solution.detections
            if det is None or len(det) == 0:
                continue
            cx, cy = principal_point(record)
            n = len(det)
            rows["set"] += [s.name] * n
            rows["record"] += [record.name] * n
            rows["index"].append(np.arange(n))
            rows["star"].append(matched_mask(record.solution))
            for key in ("x", "y", "flux", "area_px", "peak", "elongation"):
                rows[key].append(getattr(det, key))
            with np.errstate(divide="ignore", invalid="ignore"):
                rows["peak_fraction"].append(det.peak / det.flux)
            rows["radius_px"].append(np.hypot(det.x - cx, det.y - cy))
    return _columns(rows)


def star_table(result_sets: Sequence[ResultSet]) -> dict[str, NDArray]:
    """One row per matched star of every solved record: set, record, index (detection), hip,
    mag_v (catalog, estimated Johnson V), x, y, flux, area_px, peak, elongation, residual_arcsec
    (angle to the catalog star after the fit) and radius_px (from the principal point)."""
    catalog = load_catalog()
    keys = ("set", "record", "index", "hip", "mag_v", "x", "y", "flux", "area_px", "peak", "elongation",
            "residual_arcsec", "radius_px")
    rows: dict[str, list] = {k: [] for k in keys}
    for s in result_sets:
        for record in s.records:
            sol = record.solution
            if not sol.solved or sol.detections is None:
                continue
            idx, det = sol.matches.det_index, sol.detections
            cx, cy = principal_point(record)
            rows["set"] += [s.name] * len(idx)
            rows["record"] += [record.name] * len(idx)
            rows["index"].append(idx)
            rows["hip"].append(sol.matches.hip)
            rows["mag_v"].append(catalog.v_mag[np.searchsorted(catalog.hip, sol.matches.hip)])
            for key in ("x", "y", "flux", "area_px", "peak", "elongation"):
                rows[key].append(getattr(det, key)[idx])
            rows["residual_arcsec"].append(sol.residuals_arcsec)
            rows["radius_px"].append(np.hypot(det.x[idx] - cx, det.y[idx] - cy))
    return _columns(rows)


_DTYPES = {"set": object, "record": object, "star": bool, "index": np.int64, "hip": np.int64, "area_px": np.int64}


def _columns(rows: dict[str, list]) -> dict[str, NDArray]:
    """Lists of arrays (or of scalars) joined into one array per column."""
    out = {}
    for key, parts in rows.items():
        if parts and isinstance(parts[0], np.ndarray):
            out[key] = np.concatenate(parts)
        else:
            out[key] = np.asarray(parts, dtype=_DTYPES.get(key, float))
    return out


def counts_table(result_sets: Sequence[ResultSet]) -> dict[str, list]:
    """Per record: set, record, solved, n_detected, n_star, n_noise (Fowler 2013 Table 9.4's
    starlight and noise spots per image)."""
    out: dict[str, list] = {k: [] for k in ("set", "record", "solved", "n_detected", "n_star", "n_noise")}
    for s in result_sets:
        for record in s.records:
            star = matched_mask(record.solution)
            out["set"].append(s.name)
            out["record"].append(record.name)
            out["solved"].append(record.solution.solved)
            out["n_detected"].append(int(star.size))
            out["n_star"].append(int(star.sum()))
            out["n_noise"].append(int(star.size - star.sum()))
    return out
