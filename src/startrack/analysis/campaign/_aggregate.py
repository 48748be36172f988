"""Aggregates of a campaign's trials: the cells table (``cells.csv``) and the numbers behind the figures.

Rates are over every trial of a group, ERROR and LOST rows included (they count as not solved,
so a crash never raises a success rate; ``n_error`` says how many there were). Error statistics
are over the *correct* trials only (a false solve's error is that of a wrong identification, not
the tracker's accuracy); the roll percentiles are of ``|err_roll_arcsec|``. Times are over the
trials that did not fail (ERROR / LOST rows have no time). ``docs/campaign_report.md`` lists every
column.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from ...io import atomic_path
from ._folder import load_manifest, read_parts
from ._stats import PERCENTILES, percentiles, rate_upper_bound, wilson_interval

FAILED = ("ERROR", "LOST")
"""Statuses of trials that did not run to an answer (the trial raised; its worker died)."""
SIGNED = ("err_x", "err_y", "err_roll")


def pct_name(q: float) -> str:
    """Column-name form of a percentile: 50 -> "p50", 99.7 -> "p99_7"."""
    return "p" + f"{q:g}".replace(".", "_")


def read_campaign(out: str | Path) -> tuple[dict[str, Any], pa.Table]:
    """The manifest and the trial table (sorted by cell, trial) of the campaign folder ``out``.

    Raises
    ------
    InvalidInputError
        If ``out`` has no readable ``manifest.json``, one not of the manifest's shape, no finished
        trial part or a damaged one (:mod:`._folder`).
    """
    out = Path(out)
    return load_manifest(out), read_parts(out)


def as_columns(trials: pa.Table) -> dict[str, np.ndarray]:
    """Every column of ``trials`` as a numpy array (strings and lists as object arrays)."""
    return {name: trials[name].to_numpy(zero_copy_only=False) for name in trials.column_names}


def select(cols: Mapping[str, np.ndarray], rows: np.ndarray) -> dict[str, np.ndarray]:
    """The rows ``rows`` (bool mask or indices) of every column."""
    return {name: col[rows] for name, col in cols.items()}


def stage_columns(names: Sequence[str]) -> list[str]:
    """The per-stage time columns (``time_<stage>_s``) among ``names``."""
    return [n for n in names if n.startswith("time_") and n.endswith("_s") and n != "time_s"]


def _mean(values: np.ndarray) -> float:
    data = np.asarray(values, dtype=float)
    data = data[np.isfinite(data)]
    return float(data.mean()) if data.size else math.nan


def _std(values: np.ndarray) -> float:
    data = np.asarray(values, dtype=float)
    data = data[np.isfinite(data)]
    return float(data.std(ddof=1)) if data.size > 1 else math.nan


def rate_stats(cols: Mapping[str, np.ndarray], confidence: float = 0.95) -> dict[str, Any]:
    """Counts and rates of a group of trials: solved, success (Wilson interval), false solves (upper bound)."""
    n = int(cols["cell"].size)
    solved, correct = cols["solved"].astype(bool), cols["correct"].astype(bool)
    k, n_false = int(correct.sum()), int((solved & ~correct).sum())
    low, high = wilson_interval(k, n, confidence)
    rate = (lambda m: m / n) if n else (lambda m: math.nan)
    return {"n": n, "n_error": int(np.isin(cols["status"], FAILED).sum()), "n_solved": int(solved.sum()),
            "n_correct": k, "n_false": n_false, "solved_rate": rate(int(solved.sum())), "success_rate": rate(k),
            "success_low": low, "success_high": high, "false_rate": rate(n_false),
            "false_upper": rate_upper_bound(n_false, n, confidence)}


def error_stats(cols: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Percentiles of the cross-boresight and |roll| errors, mean and std of the signed errors,
    median of the solver's own sigmas: over the correct trials (arcsec)."""
    good = cols["correct"].astype(bool)
    row: dict[str, Any] = {}
    for name, values in (("err_cross", cols["err_cross_arcsec"][good]),
                         ("err_roll", np.abs(cols["err_roll_arcsec"][good]))):
        for q, v in zip(PERCENTILES, percentiles(values), strict=True):
            row[f"{name}_{pct_name(q)}_arcsec"] = float(v)
    for name in SIGNED:
        row[f"{name}_mean_arcsec"] = _mean(cols[f"{name}_arcsec"][good])
        row[f"{name}_std_arcsec"] = _std(cols[f"{name}_arcsec"][good])
    for name in ("sigma_cross", "sigma_roll"):
        row[f"{name}_p50_arcsec"] = float(percentiles(cols[f"{name}_arcsec"][good], (50,))[0])
    return row


def time_stats(cols: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """Solve-time percentiles and maximum (s), mean star counts, per-stage time medians (s)."""
    ran = ~np.isin(cols["status"], FAILED)
    times = percentiles(cols["time_s"][ran], (50, 95, 99, 100))
    row: dict[str, Any] = {f"time_{k}_s": float(v) for k, v in zip(("p50", "p95", "p99", "max"), times, strict=True)}
    row["n_stars_mean"] = _mean(cols["n_stars"][ran])
    row["n_matched_mean"] = _mean(cols["n_matched"][cols["solved"].astype(bool)])
    for name in stage_columns(list(cols)):
        row[f"{name[:-2]}_p50_s"] = float(percentiles(cols[name][ran], (50,))[0])
    return row


def group_stats(cols: Mapping[str, np.ndarray], confidence: float = 0.95) -> dict[str, Any]:
    """Every aggregate of one group of trials (:func:`rate_stats`, :func:`error_stats`, :func:`time_stats`)."""
    return {**rate_stats(cols, confidence), **error_stats(cols), **time_stats(cols)}


def cell_keys(manifest: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Per manifest cell: cell, label, the budget source (budget mode) and the swept values."""
    out = []
    for cell in manifest["cells"]:
        key = {"cell": int(cell["cell"]), "label": cell.get("label", str(cell["cell"]))}
        if manifest.get("mode") == "budget":
            key["source"] = cell.get("source")
        key.update({axis: cell["params"].get(axis) for axis in manifest.get("swept", [])})
        out.append(key)
    return out


def hashable(value: Any) -> Any:
    """A parameter value usable as a dict key (lists become tuples)."""
    return tuple(hashable(v) for v in value) if isinstance(value, list | tuple) else value


def group_rows(trials: pa.Table, manifest: Mapping[str, Any],
               key_of: Callable[[dict[str, Any]], tuple]) -> tuple[list[tuple], np.ndarray]:
    """The groups ``key_of(cell key)`` of the manifest cells, in order of first appearance, and
    each trial row's group index (-1 for a row whose cell the manifest does not list)."""
    keys = {k["cell"]: key_of(k) for k in cell_keys(manifest)}
    index = {key: g for g, key in enumerate(dict.fromkeys(keys.values()))}
    cells = trials["cell"].to_numpy(zero_copy_only=False).astype(np.int64)
    lookup = np.full(max([*keys, int(cells.max(initial=0))]) + 1, -1)
    for cell, key in keys.items():
        lookup[cell] = index[key]
    return list(index), lookup[cells]


def grouped(trials: pa.Table, manifest: Mapping[str, Any], key_of: Callable[[dict[str, Any]], tuple],
            confidence: float = 0.95) -> list[tuple[tuple, dict[str, Any]]]:
    """:func:`group_stats` of the trials pooled by ``key_of(cell key)`` (see :func:`group_rows`;
    groups without trials keep n = 0)."""
    keys, group = group_rows(trials, manifest, key_of)
    cols = as_columns(trials)
    return [(key, group_stats(select(cols, group == g), confidence)) for g, key in enumerate(keys)]


def cell_table(trials: pa.Table, manifest: Mapping[str, Any], confidence: float = 0.95) -> pa.Table:
    """One row per manifest cell: its key columns and every aggregate (module docstring).

    Parameters
    ----------
    trials : pyarrow.Table
        The trial table (``docs/campaigns.md``); cells without rows get n = 0 and NaN statistics.
    manifest : dict
        The campaign's ``manifest.json``.
    confidence : float
        Level of the Wilson interval and of the false-solve upper bound.
    """
    keys = {k["cell"]: k for k in cell_keys(manifest)}
    rows = [{**keys[key[0]], **stats} for key, stats in grouped(trials, manifest, lambda k: (k["cell"],), confidence)]
    return pa.Table.from_pylist(rows)


def format_value(value: Any) -> str:
    """A value as written in our CSV files: floats to 10 significant digits, NaN and None empty,
    bools lowercase, lists as ``[a, b]``."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, float | np.floating):
        return f"{float(value):.10g}"
    if isinstance(value, list | tuple | np.ndarray):
        return "[" + ", ".join(format_value(v) for v in value) + "]"
    return str(value)


def write_csv(table: pa.Table, path: str | Path) -> Path:
    """Write ``table`` as CSV (header row, :func:`format_value`) atomically to ``path``."""
    path = Path(path)
    with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(table.column_names)
        for row in table.to_pylist():
            writer.writerow([format_value(v) for v in row.values()])
    return path


def write_cells_csv(out: str | Path) -> Path:
    """Read the campaign in ``out`` and write its :func:`cell_table` to ``out/cells.csv`` (atomically)."""
    manifest, trials = read_campaign(out)
    return write_csv(cell_table(trials, manifest), Path(out) / "cells.csv")


def axis_table(trials: pa.Table, manifest: Mapping[str, Any], axis: str | None,
               confidence: float = 0.95) -> tuple[pa.Table, str | None, str]:
    """The aggregates against one swept axis: the numbers behind the rate and accuracy figures.

    With one more swept axis, one group per (axis value, other value): the other axis draws one
    line per value. With two or more others, the trials are pooled over them. ``axis=None`` (no
    sweep, or budget mode): one group per cell, named by its label.

    Returns
    -------
    table : pyarrow.Table
        First column the axis (or ``label``), then the line axis if any, then :func:`group_stats`.
    line : str or None
        The line axis.
    note : str
        What was pooled ("" when nothing was).
    """
    swept = list(manifest.get("swept", []))
    others = [a for a in swept if a != axis]
    if axis is None:
        names, line, note = ["label"], None, ""
    elif len(others) == 1:
        names, line, note = [axis, others[0]], others[0], ""
    else:
        names, line = [axis], None
        note = f"pooled over {', '.join(others)}" if others else ""
    rows = [{**dict(zip(names, key, strict=True)), **stats}
            for key, stats in grouped(trials, manifest, lambda k: tuple(hashable(k[n]) for n in names), confidence)]
    return pa.Table.from_pylist(rows), line, note


def curve_key(manifest: Mapping[str, Any], max_curves: int = 10) -> tuple[str, Callable[[dict[str, Any]], tuple]]:
    """How the error distributions are split into curves: per cell when there are at most
    ``max_curves`` cells, else per value of the first swept axis (pooled over the rest), else one."""
    swept = list(manifest.get("swept", []))
    if len(manifest["cells"]) <= max_curves:
        return "cell", lambda k: (k["label"],)
    if swept:
        first = swept[0]
        return f"{first} (pooled over the other axes)", lambda k: (f"{first}={format_value(k[first])}",)
    return "all trials", lambda k: ("all",)


QUANTILE_LEVELS = np.unique(np.concatenate([np.linspace(0.0, 100.0, 201), PERCENTILES]))
"""Percent levels at which the error distributions are tabulated (every 0.5 % and the marked ones)."""


def quantile_table(trials: pa.Table, manifest: Mapping[str, Any], max_curves: int = 10) -> tuple[pa.Table, str]:
    """Quantiles of the cross-boresight and |roll| errors of the correct trials per curve (see
    :func:`curve_key`): the numbers behind the cumulative distributions.

    Returns
    -------
    table : pyarrow.Table
        Long form: ``curve``, ``error`` ("cross" or "roll"), ``n``, ``percent``, ``value_arcsec``.
    split : str
        What the curves are.
    """
    split, key_of = curve_key(manifest, max_curves)
    keys, group = group_rows(trials, manifest, key_of)
    correct = trials["correct"].to_numpy(zero_copy_only=False).astype(bool)
    errors = {"cross": trials["err_cross_arcsec"].to_numpy(zero_copy_only=False),
              "roll": np.abs(trials["err_roll_arcsec"].to_numpy(zero_copy_only=False))}
    rows = []
    for g, key in enumerate(keys):
        for name, err in errors.items():
            values = err[(group == g) & correct]
            n = int(np.isfinite(values).sum())
            rows += [{"curve": key[0], "error": name, "n": n, "percent": float(q), "value_arcsec": float(v)}
                     for q, v in zip(QUANTILE_LEVELS, percentiles(values, QUANTILE_LEVELS), strict=True)] if n else []
    return pa.Table.from_pylist(rows, schema=pa.schema([("curve", pa.string()), ("error", pa.string()),
                                                       ("n", pa.int64()), ("percent", pa.float64()),
                                                       ("value_arcsec", pa.float64())])), split


def time_tables(trials: pa.Table, bins: int = 40) -> tuple[pa.Table, pa.Table]:
    """Histogram (log-spaced bins, ms) and statistics of the solve time and of each stage's time
    over the trials that ran (not ERROR / LOST): the numbers behind the time figure.

    Returns
    -------
    histogram : pyarrow.Table
        ``left_ms``, ``right_ms``, then counts: ``time_s`` (every trial that ran), ``time_s_solved``,
        ``time_s_unsolved`` and one column per stage (``time_<stage>_s``, the image level).
    summary : pyarrow.Table
        The same rows as columns: ``time``, ``n``, ``p50_ms``, ``p95_ms``, ``p99_ms``, ``max_ms``.
    """
    ran = ~np.isin(trials["status"].to_numpy(zero_copy_only=False), FAILED)
    solved = trials["solved"].to_numpy(zero_copy_only=False).astype(bool)
    time_s = trials["time_s"].to_numpy(zero_copy_only=False)
    data = {"time_s": finite_ms(time_s[ran]), "time_s_solved": finite_ms(time_s[ran & solved]),
            "time_s_unsolved": finite_ms(time_s[ran & ~solved])}
    for name in stage_columns(trials.column_names):
        data[name] = finite_ms(trials[name].to_numpy(zero_copy_only=False)[ran])
    every = np.concatenate([*data.values(), np.zeros(0)])
    positive = every[every > 0]
    lo, hi = (positive.min(), positive.max()) if positive.size else (1.0, 1.0)
    edges = np.geomspace(lo / 1.05, hi * 1.05, bins + 1)
    hist = {"left_ms": edges[:-1], "right_ms": edges[1:]}
    hist.update({n: np.histogram(np.clip(v, edges[0], edges[-1]), edges)[0] for n, v in data.items()})
    summary = [{"time": n, "n": int(v.size), **{f"{k}_ms": float(x) for k, x in zip(
        ("p50", "p95", "p99", "max"), percentiles(v, (50, 95, 99, 100)), strict=True)}} for n, v in data.items()]
    return pa.table(hist), pa.Table.from_pylist(summary)


def finite_ms(seconds: np.ndarray) -> np.ndarray:
    """The finite values of ``seconds`` in milliseconds."""
    values = np.asarray(seconds, dtype=float) * 1e3
    return values[np.isfinite(values)]


def sky_table(trials: pa.Table, n_dec: int | None = None) -> pa.Table:
    """Success and median cross-boresight error over the TRUE boresight, in equal-area bins
    (uniform in RA and in sin Dec): the numbers behind the sky maps.

    ``n_dec`` bands of declination (default: about 10 trials per bin, 3 to 36 bands) by
    ``2 n_dec`` of RA. Every trial with a known attitude counts, pooled over the cells.

    Returns
    -------
    pyarrow.Table
        Per bin: ``ra_lo_deg``, ``ra_hi_deg``, ``dec_lo_deg``, ``dec_hi_deg``, ``n``,
        ``n_correct``, ``success_rate`` (NaN when empty), ``err_cross_p50_arcsec`` (over the correct trials).
    """
    ra, dec = (trials[c].to_numpy(zero_copy_only=False) for c in ("ra_deg", "dec_deg"))
    known = np.isfinite(ra) & np.isfinite(dec)
    if n_dec is None:
        n_dec = int(np.clip(round(math.sqrt(known.sum() / 20)), 3, 36))
    ra_edges = np.linspace(0.0, 360.0, 2 * n_dec + 1)
    dec_edges = np.degrees(np.arcsin(np.linspace(-1.0, 1.0, n_dec + 1)))
    i_ra = np.clip(np.searchsorted(ra_edges, np.mod(ra[known], 360.0), side="right") - 1, 0, 2 * n_dec - 1)
    i_dec = np.clip(np.searchsorted(dec_edges, dec[known], side="right") - 1, 0, n_dec - 1)
    flat = i_dec * (2 * n_dec) + i_ra
    correct = trials["correct"].to_numpy(zero_copy_only=False)[known].astype(bool)
    err = trials["err_cross_arcsec"].to_numpy(zero_copy_only=False)[known]
    n = np.bincount(flat, minlength=2 * n_dec * n_dec)
    k = np.bincount(flat, weights=correct, minlength=n.size)
    median = np.full(n.size, np.nan)
    for b in np.flatnonzero(k):
        median[b] = np.median(err[(flat == b) & correct])
    d, r = np.divmod(np.arange(n.size), 2 * n_dec)
    with np.errstate(invalid="ignore", divide="ignore"):
        rate = np.where(n > 0, k / np.maximum(n, 1), np.nan)
    return pa.table({"ra_lo_deg": ra_edges[r], "ra_hi_deg": ra_edges[r + 1], "dec_lo_deg": dec_edges[d],
                     "dec_hi_deg": dec_edges[d + 1], "n": n, "n_correct": k.astype(np.int64),
                     "success_rate": rate, "err_cross_p50_arcsec": median})


def status_table(trials: pa.Table, manifest: Mapping[str, Any]) -> pa.Table:
    """Per cell the number of trials of each status (OK first, then alphabetical)."""
    status = trials["status"].to_numpy(zero_copy_only=False)
    names = sorted(set(status.tolist()), key=lambda s: (s != "OK", s))
    keys, group = group_rows(trials, manifest, lambda k: (k["cell"], k["label"]))
    rows = [{"cell": key[0], "label": key[1], **{s: int(((group == g) & (status == s)).sum()) for s in names}}
            for g, key in enumerate(keys)]
    return pa.Table.from_pylist(rows)
