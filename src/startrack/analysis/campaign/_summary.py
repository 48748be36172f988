"""What ``startrack campaign run`` and ``report`` print: one line per cell, the status counts, and
the seed's numbers beside ours where the spec has ``[[reference]]`` tables."""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path
from typing import Any

from ._aggregate import cell_table, read_campaign
from ._reference import reference_text

COLUMNS = (("n", "{:>6}", "n"), ("success", "{:>22}", "success [95 % CI]"), ("false", "{:>13}", "false (bound)"),
           ("cross", "{:>10}", "cross p68"), ("roll", "{:>10}", "|roll| p68"), ("time", "{:>10}", "time p50"))


def _pct(value: float) -> str:
    return "-" if math.isnan(value) else f"{100 * value:.1f}"


def _arcsec(value: float) -> str:
    return "-" if math.isnan(value) else f'{value:.3g}"'


def _cells(row: dict[str, Any]) -> dict[str, str]:
    return {"n": str(row["n"]),
            "success": f"{_pct(row['success_rate'])} % [{_pct(row['success_low'])}, {_pct(row['success_high'])}]",
            "false": f"{row['n_false']} ({_pct(row['false_upper'])} %)",
            "cross": _arcsec(row["err_cross_p68_arcsec"]), "roll": _arcsec(row["err_roll_p68_arcsec"]),
            "time": "-" if math.isnan(row["time_p50_s"]) else f"{1e3 * row['time_p50_s']:.3g} ms"}


def cells_text(rows: list[dict[str, Any]]) -> str:
    """The per-cell table (errors over correct trials; false solves with their 95 % upper bound)."""
    width = max([len("cell"), *(len(f"{r['cell']} {r['label']}") for r in rows)])
    lines = [f"{'cell':<{width}} " + " ".join(fmt.format(title) for _, fmt, title in COLUMNS)]
    for row in rows:
        text = _cells(row)
        lines.append(f"{str(row['cell']) + ' ' + row['label']:<{width}} "
                     + " ".join(fmt.format(text[key]) for key, fmt, _ in COLUMNS))
    return "\n".join(lines)


def summary_text(out: str | Path) -> str:
    """The terminal summary of the campaign in folder ``out``."""
    manifest, trials = read_campaign(out)
    rows = cell_table(trials, manifest).to_pylist()
    statuses = ", ".join(f"{name} {count}" for name, count in Counter(trials["status"].to_pylist()).most_common())
    runs = manifest.get("runs", [])
    where = (f" on {runs[-1].get('workers', '?')} workers ({runs[-1].get('mode', '?')})" if runs
             else ", a run that did not finish (--resume finishes it)")
    planned = int(manifest.get("trials_per_cell", 0)) * len(manifest["cells"])
    count = f"{trials.num_rows} of {planned}" if 0 < trials.num_rows < planned else f"{trials.num_rows}"
    head = (f"campaign {manifest['name']} (level {manifest['level']}): {count} trials in "
            f"{len(manifest['cells'])} cells{where}; status: {statuses}")
    parts = [head, cells_text(rows)]
    if manifest.get("mode") == "budget":
        from ._budget_report import budget_text

        parts.append(budget_text(out))
    reference = reference_text(out)
    if reference:
        parts.append(reference)
    return "\n\n".join(parts)
