"""The campaign report's figures, each drawn from the table of numbers behind it.

Plotting only: the numbers come from :mod:`._aggregate`. Every function returns a
:class:`matplotlib.figure.Figure` built with the object-oriented API (no pyplot, no backend
switched); :func:`report_figures` pairs each figure with its tables for the report.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import pyarrow as pa

from ...plotting import new_figure
from ._aggregate import axis_table, format_value, quantile_table, sky_table, time_tables
from ._stats import PERCENTILES

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure

DPI = 110
UNITS = (("_mag_arcsec2", "mag/arcsec²"), ("_deg_s", "deg/s"), ("_e_s", "e⁻/s"), ("_arcsec", "arcsec"),
         ("_deg", "deg"), ("_px", "px"), ("_hz", "Hz"), ("_jyear", "Julian year"), ("_e", "e⁻"), ("_s", "s"))
MARKERS = dict(zip(PERCENTILES, ("o", "s", "^", "D"), strict=True))


@dataclass(frozen=True)
class ReportFigure:
    """A figure of the report and the tables behind it.

    Attributes
    ----------
    name : str
        File stem: ``figures/<name>.png``; its tables are ``data/<name>.csv`` or ``data/<name>-<key>.csv``.
    title, caption : str
    figure : matplotlib.figure.Figure
    data : dict
        Table key ("" for the only one) -> pyarrow.Table.
    data_stem : str
        Stem of the tables' files (default ``name``; figures drawn from one table share it).
    """

    name: str
    title: str
    caption: str
    figure: Figure
    data: dict[str, pa.Table] = field(default_factory=dict)
    data_stem: str = ""

    def csv_names(self) -> dict[str, str]:
        """Table key -> path of its CSV relative to the output folder."""
        stem = self.data_stem or self.name
        return {key: f"data/{stem}{'-' + key if key else ''}.csv" for key in self.data}


def axis_label(name: str) -> str:
    """A parameter or column name as an axis label with its unit: ``fov_deg`` -> ``fov (deg)``."""
    for suffix, unit in UNITS:
        if name.endswith(suffix) and len(name) > len(suffix):
            return f"{name[: -len(suffix)].replace('_', ' ')} ({unit})"
    return name.replace("_", " ")


def value_label(name: str, value: Any) -> str:
    """``name = value unit``: ``fov_deg``, 8.0 -> ``fov = 8 deg``."""
    label = axis_label(name)
    text = format_value(list(value) if isinstance(value, tuple) else value)
    if label.endswith(")"):
        base, unit = label[:-1].rsplit(" (", 1)
        return f"{base} = {text} {unit}"
    return f"{label} = {text}"


def _numeric(values: Sequence[Any]) -> bool:
    return all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in values)


def _x_axis(ax: Axes, values: Sequence[Any], label: str) -> dict[Any, float]:
    """Position of each distinct value on the x axis (numeric values as themselves, on a log scale
    when positive and spanning a decade or more; other values as evenly spaced categories)."""
    distinct = list(dict.fromkeys(map(_key, values)))
    ax.set_xlabel(label)
    if _numeric(distinct):
        if min(distinct) > 0 and max(distinct) >= 10 * min(distinct):
            ax.set_xscale("log")
        ax.set_xticks(sorted(distinct), [format_value(float(v)) for v in sorted(distinct)])
        ax.minorticks_off()
        return {v: float(v) for v in distinct}
    ax.set_xticks(range(len(distinct)), [format_value(v) for v in distinct],
                  rotation=30 if len(distinct) > 4 else 0, ha="right" if len(distinct) > 4 else "center")
    ax.set_xlim(-0.5, len(distinct) - 0.5)
    return {v: float(i) for i, v in enumerate(distinct)}


def _key(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


def _lines(table: pa.Table, x_name: str, line: str | None) -> list[tuple[str, dict[str, np.ndarray]]]:
    """The table split into one series per value of ``line`` (one series when None), as columns."""
    rows = table.to_pylist()
    groups: dict[Any, list[dict]] = {}
    for row in rows:
        groups.setdefault(_key(row[line]) if line else None, []).append(row)
    out = []
    for value, members in groups.items():
        name = "" if line is None else value_label(line, value)
        out.append((name, {k: np.array([m[k] for m in members], dtype=object) for k in members[0]}))
    return out


def _title(fig: Figure, title: str, note: str) -> None:
    fig.suptitle(title + (f"  ({note})" if note else ""), fontsize=11)


def rates_figure(table: pa.Table, axis: str | None, line: str | None, note: str = "", title: str = "") -> Figure:
    """Success rate with its Wilson 95 % interval (left) and false-solve rate with its 95 % upper
    bound (right) against ``axis`` (``None``: per cell label), one line per value of ``line``."""
    x_name = axis or "label"
    fig = new_figure(figsize=(11, 4.3), dpi=DPI, layout="constrained")
    ax_s, ax_f = fig.subplots(1, 2)
    pos = _x_axis(ax_s, table[x_name].to_pylist(), axis_label(axis) if axis else "cell")
    _x_axis(ax_f, table[x_name].to_pylist(), axis_label(axis) if axis else "cell")
    series = _lines(table, x_name, line)
    for i, (name, s) in enumerate(series):
        x = _dodge(ax_s, np.array([pos[_key(v)] for v in s[x_name]]), i - (len(series) - 1) / 2)
        rate, low, high = (s[k].astype(float) for k in ("success_rate", "success_low", "success_high"))
        ax_s.errorbar(x, rate, yerr=np.clip([rate - low, high - rate], 0.0, None), marker="o", capsize=3,
                      label=name or None, color=f"C{i}", ls=_joined(pos, "-"))
        false, upper = s["false_rate"].astype(float), s["false_upper"].astype(float)
        ax_f.vlines(x, false, upper, color=f"C{i}", alpha=0.6)
        ax_f.plot(x, false, "o", ls=_joined(pos, "-"), color=f"C{i}", label=name or None)
        ax_f.plot(x, upper, "v", color=f"C{i}", markersize=7)
    lows = table["success_low"].to_numpy(zero_copy_only=False)
    ax_s.set_ylim(max(0.0, np.nanmin(lows, initial=1.0) - 0.05) if np.isfinite(lows).any() else 0.0, 1.01)
    ax_s.set_ylabel("success rate (correct / trials)")
    ax_s.set_title("success, Wilson 95 % interval", fontsize=10)
    uppers = table["false_upper"].to_numpy(zero_copy_only=False)
    ax_f.set_ylim(0.0, max(float(np.nanmax(uppers, initial=0.0)) * 1.15, 1e-3))
    ax_f.set_ylabel("false-solve rate (solved, not correct)")
    ax_f.set_title("false solves: seen (o), 95 % upper bound (▼, Clopper-Pearson)", fontsize=10)
    for ax in (ax_s, ax_f):
        ax.grid(True, alpha=0.3)
    if line:
        ax_s.legend(fontsize=8, loc="lower left")
    _title(fig, title or "Success and false-solve rates", note)
    return fig


def _joined(pos: dict[Any, float], style: str) -> str:
    """``style`` for points of a numeric axis (joined by lines), "none" for categories (not joined)."""
    return style if _numeric(list(pos)) else "none"


def _dodge(ax: Axes, x: np.ndarray, shift: float, step: float = 0.012) -> np.ndarray:
    """``x`` moved by ``shift`` steps of ``step`` of the axis width, so that error bars of lines at
    the same x stay apart (multiplicatively on a log axis)."""
    if ax.get_xscale() == "log":
        lo, hi = np.log10(ax.get_xlim())
        return x * 10 ** (shift * step * (hi - lo))
    lo, hi = ax.get_xlim()
    return x + shift * step * (hi - lo)


def accuracy_figure(table: pa.Table, axis: str | None, line: str | None, note: str = "", title: str = "") -> Figure:
    """Median (solid) and 95th percentile (dashed) of the cross-boresight and |roll| errors of the
    correct trials against ``axis``, on log scales."""
    x_name = axis or "label"
    fig = new_figure(figsize=(11, 4.3), dpi=DPI, layout="constrained")
    panels = fig.subplots(1, 2)
    for ax, err, label in zip(panels, ("err_cross", "err_roll"), ("cross-boresight", "|roll|"), strict=True):
        pos = _x_axis(ax, table[x_name].to_pylist(), axis_label(axis) if axis else "cell")
        for i, (name, s) in enumerate(_lines(table, x_name, line)):
            x = np.array([pos[_key(v)] for v in s[x_name]])
            ax.plot(x, s[f"{err}_p50_arcsec"].astype(float), "o", ls=_joined(pos, "-"), color=f"C{i}",
                    label=name or "median")
            ax.plot(x, s[f"{err}_p95_arcsec"].astype(float), "s", ls=_joined(pos, "--"), color=f"C{i}", alpha=0.7,
                    label=None if name else "95th percentile")
        _log_if_positive(ax, "y", [table[f"{err}_p50_arcsec"], table[f"{err}_p95_arcsec"]])
        ax.set_ylabel(f"{label} error of correct trials (arcsec)")
        ax.set_title(f"{label} error: median (o, solid), 95th percentile (■, dashed)", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    panels[0].legend(fontsize=8)
    _title(fig, title or "Accuracy", note)
    return fig


def _log_if_positive(ax: Axes, which: str, columns: Sequence[Any]) -> None:
    values = np.concatenate([np.asarray(c.to_numpy(zero_copy_only=False), dtype=float) for c in columns])
    values = values[np.isfinite(values)]
    if values.size and values.min() > 0:
        (ax.set_yscale if which == "y" else ax.set_xscale)("log")
        plain_log_labels(ax.yaxis if which == "y" else ax.xaxis)


@functools.cache
def _plain_log_formatter() -> type:
    """A ``LogFormatter`` subclass: matplotlib's choice of which log ticks to label, written as plain
    numbers (0.01, 2, 300). Defined on first use, so that matplotlib is imported only to draw."""
    from matplotlib.ticker import LogFormatter

    class PlainLogFormatter(LogFormatter):
        def __call__(self, x: float, pos: int | None = None) -> str:
            return f"{x:g}" if super().__call__(x, pos) else ""

    return PlainLogFormatter


def plain_log_labels(axis: Any) -> None:
    """Label a log axis with plain numbers, a few minor ticks too when it spans under two decades."""
    axis.set_major_formatter(_plain_log_formatter()(labelOnlyBase=False))
    axis.set_minor_formatter(_plain_log_formatter()(labelOnlyBase=False, minor_thresholds=(2, 0.5)))


def error_cdf_figure(table: pa.Table, split: str, title: str = "") -> Figure:
    """Cumulative distributions of the cross-boresight and |roll| errors of the correct trials
    (log error axis), one curve per group of ``split``, the 50/68/95/99.7 % points marked."""
    fig = new_figure(figsize=(11, 4.6), dpi=DPI, layout="constrained")
    panels = fig.subplots(1, 2, sharey=True)
    rows = table.to_pylist()
    curves = list(dict.fromkeys(r["curve"] for r in rows))
    for ax, err, label in zip(panels, ("cross", "roll"), ("cross-boresight", "|roll|"), strict=True):
        for i, curve in enumerate(curves):
            pts = [r for r in rows if r["curve"] == curve and r["error"] == err]
            if not pts:
                continue
            value = np.array([p["value_arcsec"] for p in pts])
            frac = np.array([p["percent"] for p in pts]) / 100
            ax.plot(value, frac, color=f"C{i % 10}", lw=1.4, label=f"{curve} (n = {pts[0]['n']})")
            for q, marker in MARKERS.items():
                ax.plot(value[frac == q / 100], [q / 100], marker, color=f"C{i % 10}", ms=5)
        for q in PERCENTILES:
            ax.axhline(q / 100, color="0.5", lw=0.6, ls=":")
        _log_if_positive(ax, "x", [table["value_arcsec"]])
        ax.set_xlabel(f"{label} error (arcsec)")
        ax.set_title(f"{label} error of the correct trials", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    panels[0].set_ylabel("fraction of correct trials with error <= x")
    panels[0].set_ylim(0, 1.01)
    handles = [panels[1].plot([], [], m, color="0.3", ls="")[0] for m in MARKERS.values()]
    panels[1].legend(handles, [f"{q:g} %" for q in MARKERS], title="percentiles", fontsize=8, loc="lower right")
    if panels[0].get_legend_handles_labels()[0]:  # curves with cross-boresight errors
        panels[0].legend(fontsize=7, loc="upper left")
    _title(fig, title or "Error distributions", f"curves per {split}")
    return fig


def time_figure(histogram: pa.Table, summary: pa.Table, title: str = "") -> Figure:
    """Histogram of the solve time (and of each stage when recorded), log time axis (ms), with
    the solve time's p50, p95, p99 and maximum marked."""
    fig = new_figure(figsize=(9, 4.3), dpi=DPI, layout="constrained")
    ax = fig.subplots()
    edges = np.append(histogram["left_ms"].to_numpy(), histogram["right_ms"].to_numpy()[-1:])
    ax.stairs(histogram["time_s"].to_numpy(), edges, color="C0", fill=True, alpha=0.3, label="solve time (time_s)")
    for name, label, style in (("time_s_solved", "solved", "-"), ("time_s_unsolved", "not solved", "--")):
        if histogram[name].to_numpy().any():
            ax.stairs(histogram[name].to_numpy(), edges, color="C0", ls=style, lw=1.2, label=label)
    stages = [c for c in histogram.column_names if c.startswith("time_") and c.endswith("_s") and c != "time_s"]
    for i, name in enumerate(stages):
        ax.stairs(histogram[name].to_numpy(), edges, color=f"C{i + 1}", lw=1.5,
                  label=name.removeprefix("time_").removesuffix("_s") + " stage")
    stats = {r["time"]: r for r in summary.to_pylist()}.get("time_s") or {}
    for key, style in (("p50", "-"), ("p95", "--"), ("p99", "-."), ("max", ":")) if stats else ():
        ax.axvline(stats[f"{key}_ms"], color="k", ls=style, lw=1, label=f"{key} {stats[f'{key}_ms']:.3g} ms")
    ax.set_xscale("log")
    plain_log_labels(ax.xaxis)
    ax.set_xlabel("time per trial (ms)")
    ax.set_ylabel("trials per bin")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    n = stats["n"] if stats else 0
    _title(fig, title or "Solve time", f"{n} trials that ran")
    return fig


def sky_figure(sky: pa.Table, title: str = "") -> Figure:
    """Mollweide maps of the success rate and of the median cross-boresight error over the TRUE
    boresight, in equal-area bins; RA increases to the left (centre 12h), as on the sky."""
    ra_lo, dec_lo = sky["ra_lo_deg"].to_numpy(), sky["dec_lo_deg"].to_numpy()
    n_ra, n_dec = np.unique(ra_lo).size, np.unique(dec_lo).size
    sub = max(1, math.ceil(96 / n_ra))  # sub-cells per bin, so that bin edges follow the projection's curves
    lon = np.linspace(-np.pi, np.pi, n_ra * sub + 1)
    lat = np.arcsin(np.linspace(-1.0, 1.0, n_dec * sub + 1))
    panels = [("success_rate", "success rate", "RdYlGn")]
    if np.isfinite(sky["err_cross_p50_arcsec"].to_numpy(zero_copy_only=False)).any():
        panels.append(("err_cross_p50_arcsec", "median cross-boresight error (arcsec)", "viridis"))
    fig = new_figure(figsize=(6.5 * len(panels), 4.4), dpi=DPI, layout="constrained")
    from matplotlib import colormaps  # importable: new_figure checked matplotlib
    from matplotlib.colors import LogNorm

    for i, (column, label, cmap) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), i + 1, projection="mollweide")
        grid = sky[column].to_numpy(zero_copy_only=False).astype(float).reshape(n_dec, n_ra)[:, ::-1]
        grid = np.repeat(np.repeat(grid, sub, axis=0), sub, axis=1)
        mesh = ax.pcolormesh(lon, lat, np.ma.masked_invalid(grid), cmap=colormaps[cmap].with_extremes(bad="0.85"),
                             norm=_norm(column, grid))
        bar = fig.colorbar(mesh, ax=ax, orientation="horizontal", shrink=0.6, pad=0.03, label=label)
        if isinstance(mesh.norm, LogNorm):
            plain_log_labels(bar.ax.xaxis)
        ticks = np.array([-120, -60, 0, 60, 120])
        ax.set_xticks(np.radians(ticks), [f"{(180 - t) // 15}h" for t in ticks], fontsize=8)
        ax.tick_params(axis="y", labelsize=8)
        ax.set_xlabel("RA of the true boresight (increases to the left; centre 12h)")
        ax.set_ylabel("Dec")
        ax.grid(True, alpha=0.4)
    n = int(sky["n"].to_numpy().sum())
    _title(fig, title or "Over the sky", f"{n} trials pooled over all cells, {n_ra} x {n_dec} equal-area bins; "
                                         "grey: no trial / no correct trial")
    return fig


def _norm(column: str, grid: np.ndarray) -> Normalize:
    from matplotlib.colors import LogNorm, Normalize

    if column == "success_rate":
        return Normalize(0.0, 1.0)
    good = grid[np.isfinite(grid) & (grid > 0)]
    if good.size and good.max() > 10 * good.min():
        return LogNorm(good.min(), good.max())
    return Normalize(*(good.min(), good.max()) if good.size else (0.0, 1.0))


RATES_CAPTION = ("Success: correct / trials with the Wilson 95 % interval; false solves: solved but not correct, "
                 "with the one-sided 95 % upper bound (Clopper-Pearson; about 3 / n when none was seen).")
ACCURACY_CAPTION = ("Median and 95th percentile of the cross-boresight and |roll| errors of the correct trials (the "
                    "same table as the rates).")
CDF_CAPTION = ("Cumulative distributions of the errors of the correct trials, per {split}; marks at the 50, 68, 95 "
               "and 99.7th percentiles. The table gives the quantiles every 0.5 %.")
TIME_CAPTION = ("Histogram of the time per trial (log bins) over the trials that ran; p50, p95, p99 and the maximum "
                "of the solve time marked.")
SKY_CAPTION = ("Success rate and median cross-boresight error (correct trials) against the true boresight, bins "
               "uniform in RA and sin(Dec) (equal area).")


def _axis_figures(trials: pa.Table, manifest: Mapping[str, Any], axis: str | None,
                  errors: bool) -> list[ReportFigure]:
    table, line, note = axis_table(trials, manifest, axis)
    stem, what = (f"by_{axis}", axis_label(axis)) if axis else ("by_cell", "cell")
    name = manifest.get("name", "campaign")
    pooled = f" Trials {note}." if note else ""
    out = [ReportFigure(f"rates_{stem}", f"Success and false-solve rates against {what}", RATES_CAPTION + pooled,
                        rates_figure(table, axis, line, note, f"{name}: rates against {what}"), {"": table}, stem)]
    if errors:
        out.append(ReportFigure(f"accuracy_{stem}", f"Accuracy against {what}", ACCURACY_CAPTION + pooled,
                                accuracy_figure(table, axis, line, note, f"{name}: accuracy against {what}"),
                                {"": table}, stem))
    return out


def _any_finite(trials: pa.Table, column: str, rows: np.ndarray | None = None) -> bool:
    values = np.asarray(trials[column].to_numpy(zero_copy_only=False), dtype=float)
    return bool(np.isfinite(values if rows is None else values[rows]).any())


def report_figures(trials: pa.Table, manifest: Mapping[str, Any]) -> tuple[list[ReportFigure], list[str]]:
    """Every figure of the report with its tables, in report order: rates and accuracy against each
    swept axis (per cell when nothing is swept), error distributions, solve time, sky maps.

    Returns
    -------
    figures : list of ReportFigure
    notes : list of str
        The figures left out for want of data (a level that records no attitude error, no time or
        no true boresight), and why.
    """
    name, notes = manifest.get("name", "campaign"), []
    errors = _any_finite(trials, "err_cross_arcsec", trials["correct"].to_numpy(zero_copy_only=False).astype(bool))
    if not errors:
        notes.append("No correct trial has an attitude error (this level may not solve for attitude): the accuracy "
                     "and error-distribution figures are left out.")
    axes = list(manifest.get("swept", [])) or [None]
    out = [f for axis in axes for f in _axis_figures(trials, manifest, axis, errors)]
    if errors:
        quantiles, split = quantile_table(trials, manifest)
        out.append(ReportFigure("error_cdf", "Error distributions", CDF_CAPTION.format(split=split),
                                error_cdf_figure(quantiles, split, f"{name}: error distributions"), {"": quantiles}))
    if _any_finite(trials, "time_s"):
        histogram, summary = time_tables(trials)
        out.append(ReportFigure("time", "Solve time", TIME_CAPTION,
                                time_figure(histogram, summary, f"{name}: time per trial"),
                                {"histogram": histogram, "summary": summary}))
    else:
        notes.append("No trial has a time: the time histogram is left out.")
    if _any_finite(trials, "ra_deg") and _any_finite(trials, "dec_deg"):
        sky = sky_table(trials)
        out.append(ReportFigure("sky", "Over the sky", SKY_CAPTION, sky_figure(sky, f"{name}: over the sky"),
                                {"": sky}))
    else:
        notes.append("No trial has a true boresight: the sky maps are left out.")
    return out, notes
