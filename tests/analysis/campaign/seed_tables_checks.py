"""Checks shared by the tests of the Huffman 2006 / 002 / 004 table levels and their shipped specs.

Each shipped spec must parse, hold the seed's numbers in its ``[[reference]]`` rows with each row
selecting exactly one cell, and a tiny synchronous run of it (its text edited by
``benchmarks/seed_campaign.spec_text``, which the seed-table benchmarks use too) must give the
columns its references need, every reference evaluating to a number.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

import pyarrow as pa

from startrack.analysis.campaign._reference import match_cells, reference_tables
from startrack.analysis.campaign._run import run_campaign
from startrack.analysis.campaign._shipped import find_spec
from startrack.analysis.campaign._spec import CampaignSpec, load_spec, parse_spec
from startrack.analysis.campaign._stats import parse_metric
from startrack.analysis.campaign._store import CampaignStore

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))
from seed_campaign import spec_text  # noqa: E402


def shipped(name: str) -> CampaignSpec:
    """The shipped spec ``name`` as read from its file."""
    return load_spec(find_spec(name))


def manifest_cells(spec: CampaignSpec) -> dict[str, Any]:
    """The ``cells`` part of a manifest, as :func:`match_cells` reads it."""
    return {"cells": [{"cell": c.index, "label": c.label, "params": c.params} for c in spec.cells()]}


def seed_numbers(spec: CampaignSpec, title_start: str) -> dict[tuple, Any]:
    """The seed values of the reference whose title starts with ``title_start``, keyed by the
    sorted ``where`` items of each row; every row must select exactly one cell."""
    refs = [r for r in spec.reference if r["title"].startswith(title_start)]
    assert len(refs) == 1, f"{len(refs)} references titled {title_start!r}"
    manifest = manifest_cells(spec)
    out = {}
    for row in refs[0]["rows"]:
        assert len(match_cells(manifest, row["where"])) == 1, row
        out[tuple(sorted(row["where"].items()))] = row["seed"]
    return out


def tiny_run(name: str, tmp_path: Path, *, trials: int = 1, base: dict | None = None,
             sweep: dict | None = None) -> tuple[pa.Table, dict]:
    """A synchronous run of the shipped spec with few trials (and the given edits); returns the
    trials and the reference tables' rows by title, each metric a finite number."""
    spec = parse_spec(spec_text(name, trials=trials, base=base, sweep=sweep))
    trials_table = run_campaign(spec, tmp_path / "out", sync=True, report=False)
    for ref in spec.reference:
        column = parse_metric(ref["metric"]).column
        assert column in trials_table.column_names, f"{ref['title']}: no column {column!r}"
    manifest = CampaignStore(tmp_path / "out").read_manifest()
    tables = {}
    for ref in reference_tables(trials_table, manifest, strict=False):
        assert not ref.error, ref.error
        tables[ref.title] = ref.table.to_pylist()
    return trials_table, tables


def finite(rows: list[dict]) -> bool:
    """Whether every row's ``ours`` is a finite number."""
    return all(math.isfinite(r["ours"]) for r in rows)
