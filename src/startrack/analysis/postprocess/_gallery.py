"""Analysis 2: a gallery of spots, star against noise (Fowler 2013 Ch.8 "random starlight and noise
spot pixel-cluster galleries"; Ch. 9 §V).

Up to ``count`` matched (star) and ``count`` unmatched (noise) detections are drawn at random
(seeded) from all the records, and a square stamp of ``stamp_px`` pixels around each is shown with
its own grey scale (its minimum to its maximum), labelled with the HIP number or "noise" and the
spot's area. The table lists the spots shown, with each stamp's minimum and maximum pixel value.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ...errors import InvalidInputError, require
from .._records import ImageRecord
from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._figures import new_figure, no_data
from ._records_io import record_pixels
from ._spots import matched_mask


def check(params: dict) -> None:
    """A stamp has a centre pixel: its side is odd."""
    if params["stamp_px"] % 2 == 0:
        raise InvalidInputError(f"gallery: parameter 'stamp_px' must be odd, got {params['stamp_px']}")


INFO = AnalysisInfo(
    name="gallery",
    title="Spot gallery: star spots against noise spots",
    description="Stamps around randomly chosen matched (star) and unmatched (noise) detections, each with "
                "its own grey scale, so that the shapes of starlight and noise spots can be compared. "
                "Fowler 2013 Ch. 9 §V.",
    min_sets=1, max_sets=6, needs_images=True,
    params={"count": (int, 8, "spots of each kind shown"),
            "stamp_px": (int, 15, "side of each stamp, px (odd)"),
            "seed": (int, 0, "seed of the random choice")},
    limits={"count": (1, 40), "stamp_px": (5, 101), "seed": (0, None)},
    check=check,
)
COLUMNS = 8


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    rng = np.random.default_rng(params["seed"])
    picks = {kind: _pick(sets, kind, params["count"], rng) for kind in ("star", "noise")}
    half = params["stamp_px"] // 2
    cache: dict[int, NDArray] = {}
    table: dict[str, list] = {k: [] for k in ("set", "record", "index", "spot", "hip", "x", "y", "flux",
                                              "area_px", "peak", "stamp_min", "stamp_max")}
    stamps: dict[str, list[tuple[NDArray, str]]] = {"star": [], "noise": []}
    for kind, chosen in picks.items():
        for set_name, record, i in chosen:
            pixels = cache.setdefault(id(record), np.asarray(record_pixels(record), float))
            det = require(record.solution.detections, "a spot's detections")
            stamp = _stamp(pixels, det.x[i], det.y[i], half)
            hip = _hip(record, i)
            area = int(det.area_px[i])
            stamps[kind].append((stamp, f"{f'HIP {hip}' if hip is not None else 'noise'}, {area} px"))
            _row(table, set_name, record, i, kind, hip, stamp)
    fig = _draw(stamps, params["count"])
    summary = {"star spots shown": len(picks["star"]), "noise spots shown": len(picks["noise"]),
               "star spots available": _available(sets, "star"), "noise spots available": _available(sets, "noise")}
    return AnalysisResult(INFO.name, INFO.title, fig, {"stamps": table}, summary)


def _candidates(sets, kind: str) -> list[tuple[str, ImageRecord, int]]:
    out: list[tuple[str, ImageRecord, int]] = []
    for s in sets:
        for record in s.records:
            mask = matched_mask(record.solution)
            wanted = mask if kind == "star" else ~mask
            out += [(s.name, record, int(i)) for i in np.flatnonzero(wanted)]
    return out


def _available(sets, kind: str) -> int:
    return len(_candidates(sets, kind))


def _pick(sets, kind: str, count: int, rng: np.random.Generator) -> list[tuple[str, ImageRecord, int]]:
    """Up to ``count`` spots of ``kind``, chosen at random without repetition (in table order)."""
    pool = _candidates(sets, kind)
    if len(pool) <= count:
        return pool
    return [pool[i] for i in np.sort(rng.choice(len(pool), size=count, replace=False))]


def _stamp(pixels: NDArray, x: float, y: float, half: int) -> NDArray:
    """The (2 half + 1)^2 pixels centred on the pixel nearest (x, y); NaN beyond the image."""
    h, w = pixels.shape[:2]
    cx, cy = int(round(x)), int(round(y))
    out = np.full((2 * half + 1, 2 * half + 1), np.nan)
    y0, y1, x0, x1 = max(cy - half, 0), min(cy + half + 1, h), max(cx - half, 0), min(cx + half + 1, w)
    out[y0 - cy + half:y1 - cy + half, x0 - cx + half:x1 - cx + half] = pixels[y0:y1, x0:x1]
    return out


def _hip(record, index: int) -> int | None:
    matches = record.solution.matches
    where = np.flatnonzero(matches.det_index == index)
    return int(matches.hip[where[0]]) if where.size else None


def _row(table: dict[str, list], set_name: str, record, i: int, kind: str, hip: int | None, stamp: NDArray) -> None:
    det = record.solution.detections
    values = {"set": set_name, "record": record.name, "index": i, "spot": kind, "hip": hip,
              "x": float(det.x[i]), "y": float(det.y[i]), "flux": float(det.flux[i]), "area_px": int(det.area_px[i]),
              "peak": float(det.peak[i]), "stamp_min": float(np.nanmin(stamp)), "stamp_max": float(np.nanmax(stamp))}
    for key, value in values.items():
        table[key].append(value)


def _draw(stamps: dict[str, list[tuple[NDArray, str]]], count: int):
    cols = min(COLUMNS, count)
    rows_per_kind = {k: max(1, math.ceil(len(v) / cols)) for k, v in stamps.items()}
    fig, axes = new_figure(sum(rows_per_kind.values()), cols, width_in=1.5, height_in=1.6, title=INFO.title)
    row = 0
    for kind, items in stamps.items():
        block = axes[row:row + rows_per_kind[kind]].ravel()
        for k, ax in enumerate(block):
            if k < len(items):
                stamp, label = items[k]
                ax.imshow(stamp, cmap="gray", interpolation="nearest")
                ax.set_title(label, fontsize=7)
                ax.set_xticks([])
                ax.set_yticks([])
            else:
                no_data(ax, f"no more {kind} spots" if k == len(items) else "")
                ax.set_axis_off()
        row += rows_per_kind[kind]
    return fig
