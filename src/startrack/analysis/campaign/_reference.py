"""Ours beside the seed's: the spec's ``[[reference]]`` tables evaluated against the trials.

Each reference has a ``metric`` (``AGG:COLUMN[@ROWS]``, :func:`.stats.parse_metric`) and
``rows``; each row selects cells with ``where`` (parameter = value; ``{}`` selects every cell),
pools their trials, computes the metric and sets it beside the seed's number::

    [[reference]]
    title = "Huffman 2006 Table 5.1: V limit for at least 4 stars in every field"
    source = "Huffman 2006, Table 5.1"
    metric = "min:n_stars"
    unit = "stars"
    scale = 1.0          # optional: ours is multiplied by it (e.g. 1/60 to give arcsec in arcmin)
    rows = [ { where = { max_mag = 5.0 }, seed = 4, label = "V <= 5.0", note = "..." } ]

A row may give its own ``metric``. A ``where`` value matches a parameter equal to it (numbers to
1e-9 relative); a list matches any of its values unless the parameter itself is a list. Besides
the parameters, ``cell`` (index), ``label`` and, in budget mode, ``source`` select cells.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from ...errors import InvalidInputError
from ._aggregate import as_columns, format_value, read_campaign, select
from ._stats import parse_metric

COLUMNS = ("label", "ours", "seed", "seed_value", "difference", "ratio", "n_trials", "n_used", "cells", "note")
SCHEMA = pa.schema([("label", pa.string()), ("ours", pa.float64()), ("seed", pa.string()),
                    ("seed_value", pa.float64()), ("difference", pa.float64()), ("ratio", pa.float64()),
                    ("n_trials", pa.int64()), ("n_used", pa.int64()), ("cells", pa.string()), ("note", pa.string())])


@dataclass(frozen=True)
class ReferenceTable:
    """One ``[[reference]]`` evaluated.

    Attributes
    ----------
    title, source, metric, unit : str
        As in the spec.
    table : pyarrow.Table
        One row per reference row: ``label``, ``ours`` (the metric, times ``scale``), ``seed``
        (the seed's value as text), ``seed_value`` (as a number, NaN for text), ``difference``
        (ours - seed), ``ratio`` (ours / seed), ``n_trials`` (trials of the selected cells),
        ``n_used`` (values that entered the metric), ``cells`` (their indices), ``note``.
    error : str
        Why the reference could not be evaluated ("" when it was; then ``table`` is empty).
    """

    title: str
    source: str
    metric: str
    unit: str
    table: pa.Table
    error: str = ""


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, bool) or isinstance(b, bool):
        return isinstance(a, bool) and isinstance(b, bool) and a == b
    if isinstance(a, int | float) and isinstance(b, int | float):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a == b


def _matches(value: Any, wanted: Any) -> bool:
    if isinstance(wanted, list) and not isinstance(value, list | tuple):
        return any(_same(value, w) for w in wanted)
    return _same(value, wanted)


def _cell_values(cell: Mapping[str, Any]) -> dict[str, Any]:
    values = dict(cell.get("params", {}))
    values.update(cell=cell["cell"], label=cell.get("label", ""))
    if "source" in cell:
        values["source"] = cell["source"]
    return values


def match_cells(manifest: Mapping[str, Any], where: Mapping[str, Any]) -> list[int]:
    """Indices of the manifest cells whose parameters match every ``where`` item (see the module docstring).

    Raises
    ------
    InvalidInputError
        If ``where`` is not a table or names a key no cell has.
    """
    if not isinstance(where, Mapping):
        raise InvalidInputError(f"where must be a table of parameter = value, got {where!r}")
    cells = [_cell_values(c) for c in manifest["cells"]]
    known = set().union(*(c.keys() for c in cells)) if cells else set()
    for key in where:
        if key not in known:
            raise InvalidInputError(f"where {key}: not a parameter of this campaign's cells; valid: "
                                    f"{', '.join(sorted(known))}")
    return [c["cell"] for c in cells if all(_matches(c[k], v) for k, v in where.items())]


def _seed_value(seed: Any) -> tuple[str, float]:
    if isinstance(seed, bool) or seed is None:
        return (format_value(seed), math.nan)
    if isinstance(seed, int | float):
        return (format_value(float(seed)), float(seed))
    return (str(seed), math.nan)


def _selection(row: Any, i: int, manifest: Mapping[str, Any]) -> tuple[str, list[int]]:
    """The label of reference row ``i`` and the cells it selects."""
    if not isinstance(row, Mapping):
        raise InvalidInputError(f"row {i}: must be a table {{ where = {{...}}, seed = ..., label = ... }}, got {row!r}")
    where = row.get("where", {})
    if not isinstance(where, Mapping):
        raise InvalidInputError(f"row {i}: where must be a table of parameter = value, got {where!r}")
    label = str(row.get("label") or ", ".join(f"{k}={format_value(v)}" for k, v in where.items()) or "all cells")
    cells = match_cells(manifest, where)
    if not cells:
        raise InvalidInputError(f"row {i} ({label}): where {dict(where)} selects no cell of this campaign")
    return label, cells


def _row(row: Mapping[str, Any], i: int, metric: str, scale: float, cols: Mapping[str, np.ndarray],
         manifest: Mapping[str, Any]) -> dict[str, Any]:
    label, cells = _selection(row, i, manifest)
    rows = np.isin(cols["cell"], cells)
    ours, n_used = parse_metric(row.get("metric", metric)).evaluate(select(cols, rows))
    ours *= scale
    seed_text, seed = _seed_value(row.get("seed"))
    return {"label": label, "ours": ours, "seed": seed_text, "seed_value": seed, "difference": ours - seed,
            "ratio": ours / seed if seed != 0 else math.nan, "n_trials": int(rows.sum()), "n_used": n_used,
            "cells": ",".join(map(str, cells)), "note": str(row.get("note", ""))}


def _checked_rows(reference: Mapping[str, Any], manifest: Mapping[str, Any]) -> tuple[str, float, list]:
    """The reference's metric (parsed to check it), scale and rows, each row's selection and metric checked."""
    metric = reference.get("metric", "")
    parse_metric(metric)
    scale = reference.get("scale", 1.0)
    if isinstance(scale, bool) or not isinstance(scale, int | float) or not math.isfinite(scale):
        raise InvalidInputError(f"scale must be a finite number, got {scale!r}")
    rows = reference.get("rows", [])
    if not isinstance(rows, Sequence) or isinstance(rows, str):
        raise InvalidInputError(f"rows must be a list of tables, got {rows!r}")
    for i, row in enumerate(rows):
        _selection(row, i, manifest)
        if "metric" in row:
            parse_metric(row["metric"])
    return metric, float(scale), list(rows)


def check_references(references: Sequence[Mapping[str, Any]], cells: Sequence[Any]) -> None:
    """Check a spec's ``[[reference]]`` tables before any work: every metric parses, every row is a
    table whose ``where`` names known keys and selects at least one cell, ``scale`` is a number.
    (That each metric's column exists is known only once the level has written its trials.)

    Parameters
    ----------
    references : sequence of dict
        The ``[[reference]]`` tables as read from the TOML.
    cells : sequence
        The campaign's cells: manifest dicts (``cell``, ``label``, ``params``, optional ``source``)
        or objects with ``index``, ``label``, ``params`` and ``source`` attributes (``spec.Cell``).

    Raises
    ------
    InvalidInputError
        Naming the reference and the problem.
    """
    manifest = {"cells": [c if isinstance(c, Mapping) else
                          {"cell": c.index, "label": c.label, "params": c.params,
                           **({"source": c.source} if getattr(c, "source", None) is not None else {})}
                          for c in cells]}
    for ref in references:
        try:
            _checked_rows(ref, manifest)
        except (InvalidInputError, ValueError, TypeError) as exc:
            raise InvalidInputError(f"[[reference]] {str(ref.get('title', '(untitled)'))!r}: {exc}") from None


def evaluate_reference(reference: Mapping[str, Any], trials: pa.Table, manifest: Mapping[str, Any]) -> ReferenceTable:
    """One ``[[reference]]`` against the trials (see the module docstring).

    Raises
    ------
    InvalidInputError
        For a bad metric, a ``where`` that names an unknown key or selects no cell, or bad rows,
        naming the reference and the problem.
    """
    title = str(reference.get("title", "(untitled)"))
    try:
        metric, scale, rows = _checked_rows(reference, manifest)
        cols = as_columns(trials)
        table = pa.Table.from_pylist([_row(r, i, metric, scale, cols, manifest) for i, r in enumerate(rows)],
                                     schema=SCHEMA)
    except (InvalidInputError, ValueError, TypeError) as exc:
        raise InvalidInputError(f"[[reference]] {title!r}: {exc}") from None
    return ReferenceTable(title, str(reference.get("source", "")), str(reference.get("metric", "")),
                          str(reference.get("unit", "")), table)


def reference_tables(trials: pa.Table, manifest: Mapping[str, Any], *, strict: bool = True) -> list[ReferenceTable]:
    """Every ``[[reference]]`` of the manifest's spec evaluated (an empty list when there is none).

    With ``strict=False`` a reference that cannot be evaluated comes back with its ``error`` set
    (and an empty table) instead of raising, so that a report still shows the others.
    """
    out = []
    for ref in manifest.get("spec", {}).get("reference", []):
        try:
            out.append(evaluate_reference(ref, trials, manifest))
        except InvalidInputError as exc:
            if strict:
                raise
            out.append(ReferenceTable(str(ref.get("title", "(untitled)")), str(ref.get("source", "")),
                                      str(ref.get("metric", "")), str(ref.get("unit", "")), SCHEMA.empty_table(),
                                      str(exc)))
    return out


def fmt(value: Any) -> str:
    """A number for a table cell: 4 significant digits, "-" for NaN."""
    if isinstance(value, float):
        return "-" if math.isnan(value) else f"{value:.4g}"
    return str(value)


def format_reference(ref: ReferenceTable) -> str:
    """One reference as a plain-text table (ours beside the seed's)."""
    head = [ref.title, f"  source: {ref.source or '-'}   metric: {ref.metric}" + (f" ({ref.unit})" if ref.unit else "")]
    if ref.error:
        return "\n".join([*head, f"  could not be evaluated: {ref.error}"])
    header = ("", "ours", "seed", "ours-seed", "ours/seed", "trials")
    body = [(r["label"], fmt(r["ours"]), r["seed"] or "-", fmt(r["difference"]), fmt(r["ratio"]), str(r["n_trials"]))
            for r in ref.table.to_pylist()]
    widths = [max(len(row[j]) for row in [header, *body]) for j in range(len(header))]
    lines = ["  " + "  ".join(c.ljust(w) if j == 0 else c.rjust(w) for j, (c, w) in enumerate(zip(row, widths,
                                                                                                     strict=True)))
             for row in [header, *body]]
    notes = [f"  {r['label']}: {r['note']}" for r in ref.table.to_pylist() if r["note"]]
    return "\n".join([*head, *lines, *notes])


def reference_text(out: str | Path) -> str:
    """The reference tables of the campaign in folder ``out`` as plain text ("" when the spec has none)."""
    manifest, trials = read_campaign(out)
    return "\n\n".join(format_reference(ref) for ref in reference_tables(trials, manifest, strict=False))
