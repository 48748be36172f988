"""Detection and solving run again on the records' images with changed detector settings: the
engine of the threshold comparison (analysis 7) and the parameter sweep (analysis 9).

Each record's image is detected with its own detector (:func:`.records_io.detector_of`) with one
setting changed, and solved as it was (:func:`.records_io.solve_kwargs_of`). Per value and image:
solved, detections, matches, rms residual, time (detection + identification,
``AttitudeSolution.solve_time_s``), and for the stars matched both in the record and in the re-run
(same HIP number) the mean change of their residual (Fowler 2013 Ch. 9 §VII's threshold error).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from ...detect import StarDetector
from ...errors import InvalidInputError
from ...results import AttitudeSolution
from ...solve import solve_image
from ._core import ResultSet
from ._figures import new_figure, no_data
from ._records_io import detector_of, record_pixels, solve_kwargs_of

PER_IMAGE = ("set", "record", "value", "solved", "n_detected", "n_matched", "residual_rms_arcsec", "time_s",
             "n_common", "residual_change_arcsec")
PER_VALUE = ("value", "images", "success_rate", "mean_detected", "mean_matched", "median_residual_arcsec",
             "median_time_s", "mean_residual_change_arcsec")


def detectors_for(analysis: str, param: str, record, setting: str, values: Sequence[Any]) -> list[StarDetector]:
    """The record's detector with ``setting`` set to each value; an invalid value is refused
    naming the analysis parameter ``param``."""
    base = detector_of(record)
    out = []
    for value in values:
        try:
            out.append(replace(base, **{setting: value}))
        except (InvalidInputError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"{analysis}: parameter {param!r}: {setting}={value!r} is refused: "
                                    f"{' '.join(str(exc).split())}") from None
    return out


def rerun(analysis: str, param: str, sets: Sequence[ResultSet], setting: str,
          values: Sequence[Any]) -> dict[str, list]:
    """The per-image table (:data:`PER_IMAGE`) of every record at every value."""
    jobs = [(s.name, r, detectors_for(analysis, param, r, setting, values)) for s in sets for r in s.records]
    table: dict[str, list] = {k: [] for k in PER_IMAGE}
    for set_name, record, detectors in jobs:
        if record.solution.detections is None:  # unreadable: nothing to re-run
            continue
        pixels = record_pixels(record)
        kwargs = solve_kwargs_of(record)
        for value, detector in zip(values, detectors, strict=True):
            solution = solve_image(pixels, detector=detector, **kwargs)
            _append(table, set_name, record, value, solution)
    return table


def _append(table: dict[str, list], set_name: str, record, value, solution: AttitudeSolution) -> None:
    n_common, change = _residual_change(record.solution, solution)
    rms = float(np.sqrt(np.mean(solution.residuals_arcsec**2))) if solution.solved else float("nan")
    row = (set_name, record.name, value, solution.solved,
           len(solution.detections) if solution.detections is not None else 0, len(solution.matches)
           if solution.solved else 0, rms, solution.solve_time_s, n_common, change)
    for key, item in zip(PER_IMAGE, row, strict=True):
        table[key].append(item)


def _residual_change(before: AttitudeSolution, after: AttitudeSolution) -> tuple[int, float]:
    """Stars matched in both (by HIP) and the mean of their residual after minus before, arcsec."""
    if not (before.solved and after.solved):
        return 0, float("nan")
    common, i, j = np.intersect1d(before.matches.hip, after.matches.hip, return_indices=True)
    if common.size == 0:
        return 0, float("nan")
    return int(common.size), float(np.mean(after.residuals_arcsec[j] - before.residuals_arcsec[i]))


def per_value(table: dict[str, list], values: Sequence[Any]) -> dict[str, list]:
    """The per-value summary (:data:`PER_VALUE`) of a per-image table."""
    out: dict[str, list] = {k: [] for k in PER_VALUE}
    column = {k: np.asarray(v, dtype=object if k in ("set", "record", "value") else float) for k, v in table.items()}
    for value in values:
        mask = np.array([v == value for v in table["value"]], dtype=bool)
        solved = column["solved"][mask].astype(bool)
        residual = column["residual_rms_arcsec"][mask][solved]
        change = column["residual_change_arcsec"][mask]
        change = change[np.isfinite(change)]
        row = (value, int(mask.sum()), _mean(solved), _mean(column["n_detected"][mask]),
               _mean(column["n_matched"][mask]), float(np.median(residual)) if residual.size else float("nan"),
               float(np.median(column["time_s"][mask])) if mask.any() else float("nan"), _mean(change))
        for key, item in zip(PER_VALUE, row, strict=True):
            out[key].append(item)
    return out


def _mean(values) -> float:
    values = np.asarray(values, float)
    return float(np.mean(values)) if values.size else float("nan")


def draw_per_value(summary: dict[str, list], x_label: str, title: str):
    """Success, detections and matches, residual and time against the value, four panels."""
    fig, axes = new_figure(2, 2, width_in=4.6, height_in=3.3, title=title)
    values = summary["value"]
    numeric = all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
    x = np.asarray(values, float) if numeric else np.arange(len(values))
    panels = ((("success_rate", "success rate"),), (("mean_detected", "detections"), ("mean_matched", "matches")),
              (("median_residual_arcsec", "median rms residual, arcsec"),), (("median_time_s", "median time, s"),))
    for ax, lines in zip(axes.ravel(), panels, strict=True):
        if not values:
            no_data(ax)
            continue
        for key, label in lines:
            ax.plot(x, summary[key], marker="o", label=label)
        ax.set_ylabel(lines[0][1] if len(lines) == 1 else "per image (mean)")
        ax.set_xlabel(x_label)
        if not numeric:
            ax.set_xticks(x, [str(v) for v in values])
        if len(lines) > 1:
            ax.legend(fontsize=8)
    axes[0, 0].set_ylim(-0.05, 1.05)
    return fig
