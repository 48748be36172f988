"""Analysis 4: spot properties of the matched stars against their catalog magnitude and against
their distance from the principal point (Fowler 2013 Ch.8 "Spot properties", Ch. 9 §V and App. C).

Volume (flux), area, peak and elongation of every matched spot, against the catalog's V magnitude
(``startrack.catalog``, estimated Johnson V of the Hipparcos star matched) and against the radius.
The summary gives per result set the photometric zero point and its robust scatter
(:func:`startrack.detect._magnitude.calibrate_zero_point`: the magnitude of a spot of volume 1) and
the slope of log10(volume) against magnitude (-0.4 for a linear detector), and the per-image
table the mean radius of the matched spots (Fowler 2013 Fig. 9.23's "average radial distance").
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ...detect import calibrate_zero_point
from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._figures import colour, new_figure
from ._spots import star_table

INFO = AnalysisInfo(
    name="magnitude",
    title="Spot properties against catalog magnitude and radius",
    description="Volume (flux), area, peak and elongation of the matched spots against the catalog V "
                "magnitude of their star and against their distance from the principal point, one colour "
                "per result set; the photometric zero point and the slope of log10(volume) against "
                "magnitude (-0.4 for a linear detector). Fowler 2013 Ch. 9 §V, App. C.",
    min_sets=1, max_sets=6,
)
PROPERTIES = (("flux", "volume (flux), counts", True), ("area_px", "area, px", False),
              ("peak", "peak, counts", True), ("elongation", "elongation", False))


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    stars = star_table(sets)
    fig, axes = new_figure(2, 4, width_in=3.6, title=INFO.title)
    summary: dict[str, float | int | str] = {}
    for i, s in enumerate(sets):
        mask = stars["set"] == s.name
        for col, (key, label, log) in enumerate(PROPERTIES):
            for row, (x_key, x_label) in enumerate((("mag_v", "catalog V magnitude"),
                                                     ("radius_px", "distance from the principal point, px"))):
                ax = axes[row, col]
                ax.scatter(stars[x_key][mask], stars[key][mask], s=6, color=colour(i), alpha=0.6,
                           label=s.name if col == 0 else None)
                ax.set_yscale("log" if log else "linear")
                ax.set_xlabel(x_label)
                ax.set_ylabel(label)
        summary.update(_photometry(s.name, stars["flux"][mask], stars["mag_v"][mask]))
    for row in range(2):
        if stars["hip"].size:
            axes[row, 0].legend(fontsize=7)
    tables: dict[str, Any] = {"stars": stars, "per_image": _per_image(stars)}
    return AnalysisResult(INFO.name, INFO.title, fig, tables, summary)


def _photometry(name: str, flux, mag) -> dict[str, float | int]:
    use = (flux > 0) & np.isfinite(mag)
    out: dict[str, float | int] = {f"{name}: stars": int(use.sum())}
    if use.sum() >= 1:
        zero_point, scatter = calibrate_zero_point(flux[use], mag[use])
        out[f"{name}: zero point, mag"] = zero_point
        out[f"{name}: zero point scatter, mag"] = scatter
    if use.sum() >= 3 and np.ptp(mag[use]) > 0:
        slope = np.polyfit(mag[use], np.log10(flux[use]), 1)[0]
        out[f"{name}: slope of log10(volume), per mag"] = float(slope)
    return out


def _per_image(stars) -> dict[str, list]:
    out: dict[str, list] = {k: [] for k in ("set", "record", "n_stars", "mean_radius_px", "rms_residual_arcsec")}
    keys = list(dict.fromkeys(zip(stars["set"], stars["record"], strict=True)))
    for set_name, record in keys:
        mask = (stars["set"] == set_name) & (stars["record"] == record)
        out["set"].append(set_name)
        out["record"].append(record)
        out["n_stars"].append(int(mask.sum()))
        out["mean_radius_px"].append(float(np.mean(stars["radius_px"][mask])))
        out["rms_residual_arcsec"].append(float(np.sqrt(np.mean(stars["residual_arcsec"][mask] ** 2))))
    return out
