"""The error budget in the report and on the terminal: a table and a bar chart per case.

:func:`budget_section` is registered in :data:`startrack.analysis.campaign._report.SECTIONS`
(imported with :mod:`._budget`, which the report imports in budget mode); it writes
``data/budget.csv`` (:func:`startrack.analysis.campaign._budget.budget_rows`, every case, cell and
term) and ``figures/budget.png``. :func:`budget_text` is the same table as plain text.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from ...plotting import new_figure
from ._aggregate import as_columns, read_campaign
from ._budget_terms import AXES, TERMS, budget_rows
from ._figures import ReportFigure
from ._report import esc, html_table, register_section, save_figure

TERM_NAMES = {"bias": "bias", "fov_spatial": "FOV spatial", "pixel_spatial": "pixel spatial",
              "temporal": "temporal noise", "total": "total"}
SHORT = {"bias": "bias", "fov_spatial": "fov", "pixel_spatial": "pix", "temporal": "tn", "total": "tot"}
TERM_COLOURS = {"bias": "#4c72b0", "fov_spatial": "#dd8452", "pixel_spatial": "#55a868", "temporal": "#c44e52"}
CAPTION = ("Each source's contribution to the cross-boresight (2-axis) and roll error, in arcsec, split into the "
           "ECSS-E-ST-60-20C terms: the root-sum-square difference between the source's cell and the all-off "
           "baseline, term by term (a negative estimate, within the statistics of the baseline, is not drawn); "
           "the bias as the size of the shift of the mean error; the black tick is the RMS total's contribution. "
           "See docs/error_budget.md.")


def budget_table(manifest: Mapping[str, Any], trials: pa.Table) -> pa.Table:
    """The budget rows (:func:`.budget.budget_rows`) of a campaign as a table."""
    return pa.Table.from_pylist(budget_rows(as_columns(trials), manifest["budget"]))


ZERO_ARCSEC = 1e-6
"""Sizes below this are rounding left over from differences of equal numbers: shown as 0."""
LOG_SPAN = 1e4
"""The bar chart turns logarithmic when the contributions span more than 100, and shows this range
below its largest (smaller bars are too small to matter beside it)."""


def _num(value: float) -> str:
    if not math.isfinite(value):
        return "-"
    return "0" if abs(value) < ZERO_ARCSEC else f"{value:.3g}"


def _bars(ax, rows: Sequence[Mapping[str, Any]], axis: str) -> None:
    terms = [t for t in TERMS if t != "total"]
    x = np.arange(len(rows))
    width = 0.8 / len(terms)
    for j, term in enumerate(terms):
        values = np.array([r[f"contrib_{axis}_{term}_arcsec"] for r in rows], dtype=float)
        shown = np.where(np.isfinite(values) & (values > ZERO_ARCSEC), values, np.nan)
        ax.bar(x - 0.4 + (j + 0.5) * width, shown, width, label=TERM_NAMES[term], color=TERM_COLOURS[term])
    totals = np.array([r[f"contrib_{axis}_total_arcsec"] for r in rows], dtype=float)
    ax.scatter(x, np.where(totals > ZERO_ARCSEC, totals, np.nan), marker="_", s=400, color="k", label="total", zorder=3)
    positive = np.array([r[f"contrib_{axis}_{t}_arcsec"] for r in rows for t in TERMS], dtype=float)
    positive = positive[np.isfinite(positive) & (positive > ZERO_ARCSEC)]
    if positive.size and positive.max() / positive.min() > 100.0:
        ax.set_yscale("log")
        ax.set_ylim(bottom=max(positive.min(), positive.max() / LOG_SPAN) / 2.0)
    ax.set_xticks(x, [r["source"] for r in rows], rotation=35, ha="right")
    ax.set_ylabel(f"{axis} contribution (arcsec)")
    ax.grid(axis="y", alpha=0.3)


def budget_figure(table: pa.Table) -> ReportFigure:
    """Grouped bars per source (all-on first), one row of (cross, roll) panels per case."""
    rows = [r for r in table.to_pylist() if r["source"] not in ("baseline", "sum")]
    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig = new_figure(figsize=(11, 3.8 * len(cases)), layout="constrained")
    axes = fig.subplots(len(cases), 2, squeeze=False)
    for i, case in enumerate(cases):
        mine = [r for r in rows if r["case"] == case]
        for j, axis in enumerate(AXES):
            _bars(axes[i, j], mine, axis)
            axes[i, j].set_title(f"{case}: {axis}" if len(cases) > 1 else axis)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=len(labels), fontsize="small")
    return ReportFigure("budget", "Error budget", CAPTION, fig, {"": table})


def _case_rows(rows: Sequence[Mapping[str, Any]], case: Mapping[str, Any]) -> list[list[str]]:
    out = []
    for r in (r for r in rows if r["case"] == case["name"]):
        own = r["source"] == "baseline"
        key = "{}_{}_arcsec" if own else "contrib_{}_{}_arcsec"
        values = [_num(r[key.format(axis, term)]) for axis in AXES for term in TERMS]
        words = {"baseline": ("every source off", ""), "all": ("", "every source on"),
                 "sum": ("", "the sources combined (bias as vectors, the rest in quadrature)")}.get(
            r["source"], (case["off"].get(r["source"], ""), case["on"].get(r["source"], "")))
        out.append([r["source"], *words, str(r["n_used"]) if r["source"] != "sum" else "", *values])
    return out


def _header() -> list[str]:
    return ["source", "off", "on", "n", *(f"{a} {TERM_NAMES[t]}" for a in AXES for t in TERMS)]


def _ratios(rows: Sequence[Mapping[str, Any]], case: str) -> str:
    rss = next(r for r in rows if r["case"] == case and r["source"] == "sum")
    return ", ".join(f"{axis} {_num(rss[f'ratio_{axis}_total'])}" for axis in AXES)


@register_section
def budget_section(manifest: dict[str, Any], trials: pa.Table, out: Path) -> str | None:
    """The report's error-budget section (None for a campaign that is not a budget)."""
    if manifest.get("mode") != "budget" or "budget" not in manifest:
        return None
    table = budget_table(manifest, trials)
    png, csvs = save_figure(budget_figure(table), out)
    rows, budget = table.to_pylist(), manifest["budget"]
    parts = [f"<h2>Error budget</h2><p>{budget['fields']} star fields x {budget['dithers']} dithers x "
             f"{budget['repeats']} frames per cell (correct trials only). The baseline row gives its own terms; "
             "every other row its contribution against the baseline (root-sum-square difference, arcsec; "
             "negative: below the baseline). Cross-boresight figures are 2-axis (x and y together).</p>"]
    for case in budget["cases"]:
        parts.append(f"<h3>{esc(case['name'])}</h3>" + html_table(_header(), _case_rows(rows, case), left=3)
                     + f"<p>All-on total over the sources combined (in quadrature): {esc(_ratios(rows, case['name']))}"
                     " (1: they add so).</p>")
    parts.append(f'<figure><img src="{esc(png)}" alt="error budget"><figcaption>{esc(CAPTION)} Numbers: '
                 + ", ".join(f'<a href="{esc(c)}">{esc(Path(c).name)}</a>' for c in csvs) + "</figcaption></figure>")
    return "".join(parts)


def _text_table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(row[j]) for row in [header, *rows]) for j in range(len(header))]
    return "\n".join("  " + "  ".join(c.ljust(w) if j == 0 else c.rjust(w) for j, (c, w) in
                                      enumerate(zip(row, widths, strict=True))) for row in [header, *rows])


def budget_text(out: str | Path) -> str:
    """The error budget of the campaign in folder ``out`` as plain text ("" when it is no budget)."""
    manifest, trials = read_campaign(out)
    if manifest.get("mode") != "budget" or "budget" not in manifest:
        return ""
    rows = budget_table(manifest, trials).to_pylist()
    budget = manifest["budget"]
    header = ["source", "n", *(f"{a[0]}:{SHORT[t]}" for a in AXES for t in TERMS)]
    parts = [f"error budget (arcsec; {budget['fields']} fields x {budget['dithers']} dithers x {budget['repeats']} "
             "frames; baseline: its own terms, others: contribution against it; c = cross (2-axis), r = roll; "
             "fov = FOV spatial error, pix = pixel spatial error, tn = temporal noise, tot = RMS total)"]
    for case in budget["cases"]:
        body = [[r[0], r[3], *r[4:]] for r in _case_rows(rows, case)]
        parts.append(f"{case['name']}:\n{_text_table(header, body)}\n  all-on total / the sources combined: "
                     f"{_ratios(rows, case['name'])}")
        parts.append("\n".join(f"  {s}: off = {case['off'][s]}; on = {case['on'][s]}" for s in case["sources"]))
    return "\n\n".join(parts)
