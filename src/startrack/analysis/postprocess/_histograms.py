"""Analysis 1: the image histogram and the spot histograms (Fowler 2013 Ch.8 "Histograms", Ch. 9
§IV-V; Table 9.4's starlight and noise spots per image).

For each result set, overlaid: the histogram of pixel values of all its images (log counts), and
for star and noise spots separately (:mod:`._spots`) the histograms of volume (flux, log bins),
area, peak fraction and elongation; bins are shared between the sets so that they compare bin by
bin.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._figures import colour, new_figure, no_data, shared_bins
from ._records_io import record_pixels
from ._spots import counts_table, detection_table

INFO = AnalysisInfo(
    name="histograms",
    title="Image and spot histograms",
    description="Pixel values of the images (log counts) and, for star spots (matched) and noise spots "
                "(unmatched), the volume (flux), area, peak fraction (peak / volume) and elongation; one "
                "colour per result set, stars solid and noise dashed. Fowler 2013 Ch. 9 §IV-V.",
    min_sets=1, max_sets=6,
    params={"bins": (int, 30, "bins of each spot histogram"),
            "image_bins": (int, 256, "bins of the image histogram (one per value when the range allows)"),
            "image": (bool, True, "include the image histogram (reads the pixels)")},
    limits={"bins": (2, 500), "image_bins": (2, 65536)},
)
QUANTITIES = (("flux", "volume (flux), counts", True, False), ("area_px", "area, px", False, True),
              ("peak_fraction", "peak fraction (peak / volume)", False, False),
              ("elongation", "elongation (long / short axis)", False, False))
"""(column, axis label, log bins, whole-number bins)."""


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    spots = detection_table(sets)
    fig, axes = new_figure(2, 3, title=INFO.title)
    histograms = _spot_histograms(sets, spots, params["bins"], axes.ravel()[1:5])
    tables: dict[str, Any] = {"spots": spots, "spot_histograms": histograms,
              "counts": counts_table(sets)}
    ax_image = axes[0, 0]
    if params["image"]:
        tables["image_histogram"] = _image_histogram(sets, params["image_bins"], ax_image)
    else:
        no_data(ax_image, "image histogram not asked for")
    _draw_counts(axes[1, 2], sets, tables["counts"])
    return AnalysisResult(INFO.name, INFO.title, fig, tables, _summary(sets, tables["counts"], spots))


def _spot_histograms(sets, spots, bins: int, axes) -> dict[str, list]:
    out: dict[str, list] = {k: [] for k in ("set", "quantity", "spot", "bin_low", "bin_high", "count")}
    for ax, (key, label, log, integer) in zip(axes, QUANTITIES, strict=True):
        edges = shared_bins([np.asarray(spots[key], float)], bins, log=log, integer=integer)
        for i, s in enumerate(sets):
            in_set = spots["set"] == s.name
            for kind, mask, style in (("star", spots["star"], "-"), ("noise", ~spots["star"], "--")):
                values = np.asarray(spots[key][in_set & mask], float)
                counts, _ = np.histogram(values[np.isfinite(values)], bins=edges)
                ax.stairs(counts, edges, color=colour(i), linestyle=style, label=f"{s.name} {kind}")
                _extend(out, s.name, key, kind, edges, counts)
        ax.set_xscale("log" if log and edges[0] > 0 else "linear")
        ax.set_xlabel(label)
        ax.set_ylabel("spots")
        ax.legend(fontsize=7)
    return out


def _extend(out: dict[str, list], set_name: str, quantity: str, kind: str, edges, counts) -> None:
    n = len(counts)
    out["set"] += [set_name] * n
    out["quantity"] += [quantity] * n
    out["spot"] += [kind] * n
    out["bin_low"] += list(edges[:-1])
    out["bin_high"] += list(edges[1:])
    out["count"] += [int(c) for c in counts]


def _image_histogram(sets, bins: int, ax) -> dict[str, list]:
    """Pixel-value histogram of each set (its images summed), on shared bins."""
    pixels = {s.name: [np.asarray(record_pixels(r), float).ravel() for r in s.records if _has_pixels(r)]
              for s in sets}
    edges = shared_bins([np.concatenate(v) for v in pixels.values() if v], bins, integer=True)
    out: dict[str, list] = {k: [] for k in ("set", "bin_low", "bin_high", "count")}
    for i, s in enumerate(sets):
        counts = sum((np.histogram(p[np.isfinite(p)], bins=edges)[0] for p in pixels[s.name]),
                     np.zeros(len(edges) - 1, dtype=np.int64))
        ax.stairs(counts, edges, color=colour(i), label=s.name)
        out["set"] += [s.name] * len(counts)
        out["bin_low"] += list(edges[:-1])
        out["bin_high"] += list(edges[1:])
        out["count"] += [int(c) for c in counts]
    if any(c > 0 for c in out["count"]):  # a log axis needs a positive count (no pixels: none)
        ax.set_yscale("log")
    ax.set_xlabel("pixel value, counts")
    ax.set_ylabel("pixels")
    ax.legend(fontsize=7)
    return out


def _has_pixels(record) -> bool:
    return record.image is not None or (record.path is not None and record.solution.detections is not None)


def _draw_counts(ax, sets, counts: dict[str, list]) -> None:
    """Star and noise spots per image, one bar pair per image in order."""
    names = np.asarray(counts["set"], dtype=object)
    offset = 0
    for i, s in enumerate(sets):
        mask = names == s.name
        n = int(mask.sum())
        x = offset + np.arange(n)
        ax.bar(x, np.asarray(counts["n_star"])[mask], color=colour(i), label=f"{s.name} star")
        ax.bar(x, np.asarray(counts["n_noise"])[mask], bottom=np.asarray(counts["n_star"])[mask], color=colour(i),
               alpha=0.35, label=f"{s.name} noise")
        offset += n
    ax.set_xlabel("image")
    ax.set_ylabel("spots per image")
    ax.legend(fontsize=7)


def _summary(sets, counts: dict[str, list], spots) -> dict[str, float | int | str]:
    out: dict[str, float | int | str] = {}
    names = np.asarray(counts["set"], dtype=object)
    for s in sets:
        mask = names == s.name
        star_area = np.asarray(spots["area_px"][(spots["set"] == s.name) & spots["star"]], float)
        out[f"{s.name}: images"] = int(mask.sum())
        out[f"{s.name}: star spots per image"] = float(np.mean(np.asarray(counts["n_star"])[mask]))
        out[f"{s.name}: noise spots per image"] = float(np.mean(np.asarray(counts["n_noise"])[mask]))
        out[f"{s.name}: median star area, px"] = float(np.median(star_area)) if star_area.size else float("nan")
    return out
