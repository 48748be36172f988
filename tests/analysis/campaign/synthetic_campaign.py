"""Synthetic campaign folders for the report tests: a manifest and Parquet trial parts written
to the output-folder contract (docs/campaigns.md), with outcomes drawn from a seeded generator
so that every aggregate can be checked against an independent numpy computation."""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

GOOD = {"title": "seed 999 Table 1: accuracy", "source": "a made-up seed", "metric": "p95:err_cross_arcsec",
        "unit": "arcsec", "rows": [
            {"where": {"fov_deg": 10.0}, "seed": 2.5, "label": "FOV 10", "note": "both noises"},
            {"where": {"fov_deg": 20.0, "centroid_sigma_px": 0.5}, "seed": "n/a"},
            {"where": {"centroid_sigma_px": [0.1, 0.5], "fov_deg": 20}, "seed": 0.9, "metric": "rate:correct"},
            {"where": {}, "seed": 0, "metric": "min:n_stars"}]}
BAD = {"title": "broken", "metric": "average:err_cross_arcsec", "rows": [{"where": {}, "seed": 1}]}
"""Two [[reference]] tables for a fov_deg x centroid_sigma_px sweep: one good (four kinds of row), one broken."""

TRACEBACK = 'Traceback (most recent call last):\n  File "x.py", line 1, in f\nRuntimeError: synthetic failure\n'


def make_manifest(sweep: dict[str, list[Any]], trials: int, *, name: str = "synthetic", mode: str = "sweep",
                  reference: list[dict] | None = None, finished: bool = True,
                  sources: list[str] | None = None) -> dict[str, Any]:
    """A manifest of the product of ``sweep`` (budget mode: one cell per source, nothing swept)."""
    base = {"fov_deg": 15.0, "centroid_sigma_px": 0.2, "max_mag": 6.0, "fov_range_deg": [5.0, 35.0]}
    if sources is not None:
        cells = [{"cell": i, "label": s, "params": dict(base), "source": s} for i, s in enumerate(sources)]
    else:
        combos = list(itertools.product(*sweep.values()))
        cells = [{"cell": i, "label": ", ".join(f"{k}={v:g}" for k, v in zip(sweep, combo, strict=True)) or "base",
                  "params": {**base, **dict(zip(sweep, combo, strict=True))}} for i, combo in enumerate(combos)]
    spec = {"campaign": {"name": name, "level": "stars", "trials": trials, "seed": 1, "mode": mode},
            "base": {}, "sweep": sweep, "budget": {}, "reference": reference or []}
    return {"format": "startrack-campaign/1", "name": name, "level": "stars", "mode": mode, "spec": spec,
            "spec_text": f'[campaign]\nname = "{name}"\n', "swept": list(sweep), "cells": cells,
            "trials_per_cell": trials, "seed": 1,
            "correct": {"tolerance_px": 5.0, "definition": "within 5 pixel angles"},
            "package_version": "0.0.test", "git_commit": None, "catalog_hash": "abc", "database_hashes": ["d1"],
            "started_utc": "2026-01-01T00:00:00Z", "finished_utc": "2026-01-01T00:01:00Z" if finished else None,
            "hosts": ["testhost"], "workers": 2, "chunk_size": 10}


def cell_rows(cell: dict[str, Any], swept: list[str], trials: int, rng: np.random.Generator, *,
              p_correct: float = 0.8, p_false: float = 0.05, n_error: int = 0, stages: bool = False) -> dict:
    """Columns of one cell's trials: statuses drawn with the given rates, the first ``n_error``
    trials ERROR rows, errors scaled by the cell's centroid noise."""
    u = rng.random(trials)
    correct = u < p_correct
    solved = u < p_correct + p_false
    status = np.where(solved, "OK", np.where(rng.random(trials) < 0.5, "NO_MATCH", "TOO_FEW_STARS")).astype(object)
    status[:n_error] = "ERROR"
    solved[:n_error] = correct[:n_error] = False
    scale = 5.0 * cell["params"]["centroid_sigma_px"]
    ex, ey, ez = (rng.normal(0.3, scale, trials), rng.normal(0, scale, trials), rng.normal(0, 20 * scale, trials))
    wrong = solved & ~correct
    ex[wrong] += 3600.0 * 5
    for e in (ex, ey, ez):
        e[~solved] = np.nan
    cols = {"cell": np.full(trials, cell["cell"], np.int32), "trial": np.arange(trials, dtype=np.int32)}
    cols.update({axis: [cell["params"][axis]] * trials for axis in swept})
    cols.update(status=status.tolist(), error=[TRACEBACK if s == "ERROR" else "" for s in status],
                solved=solved, correct=correct, err_x_arcsec=ex, err_y_arcsec=ey, err_roll_arcsec=ez,
                err_cross_arcsec=np.hypot(ex, ey), err_total_arcsec=np.sqrt(ex**2 + ey**2 + ez**2),
                sigma_cross_arcsec=np.where(solved, scale, np.nan),
                sigma_roll_arcsec=np.where(solved, 20 * scale, np.nan),
                n_stars=rng.integers(5, 30, trials).astype(np.int32),
                n_matched=np.where(solved, rng.integers(4, 20, trials), 0).astype(np.int32),
                false_match_prob=np.where(solved, 1e-9, 1.0),
                time_s=np.where(status == "ERROR", np.nan, rng.lognormal(np.log(2e-3), 0.5, trials)),
                ra_deg=rng.uniform(0, 360, trials), dec_deg=np.degrees(np.arcsin(rng.uniform(-1, 1, trials))),
                roll_deg=rng.uniform(-180, 180, trials), wall_s=rng.uniform(0.01, 0.02, trials))
    if stages:
        cols["time_detect_s"] = cols["time_s"] * 0.4
        cols["time_identify_s"] = cols["time_s"] * 0.6
    return cols


def write_campaign(out: Path, manifest: dict[str, Any], per_cell: list[dict]) -> Path:
    """Write ``manifest.json`` and two Parquet parts per cell (first and second half of its trials)."""
    (out / "trials").mkdir(parents=True, exist_ok=True)
    (out / "manifest.json").write_text(json.dumps(manifest, indent=1))
    for cols in per_cell:
        table = pa.table(cols)
        cell = int(cols["cell"][0])
        half = table.num_rows // 2
        for start, part in ((0, table.slice(0, half)), (half, table.slice(half))):
            pq.write_table(part, out / "trials" / f"part-{cell:05d}-{start:06d}.parquet")
    return out


def synthetic_campaign(out: Path, sweep: dict[str, list[Any]], trials: int = 40, seed: int = 3,
                       **kwargs: Any) -> tuple[dict[str, Any], list[dict]]:
    """Write a sweep campaign; ``kwargs`` go to :func:`make_manifest` (reference, finished, name) and
    :func:`cell_rows` (p_correct, p_false, n_error, stages). Returns the manifest and the per-cell columns."""
    rows_keys = ("p_correct", "p_false", "n_error", "stages")
    row_kw = {k: kwargs.pop(k) for k in rows_keys if k in kwargs}
    manifest = make_manifest(sweep, trials, **kwargs)
    rng = np.random.default_rng(seed)
    per_cell = [cell_rows(c, manifest["swept"], trials, rng, **row_kw) for c in manifest["cells"]]
    write_campaign(out, manifest, per_cell)
    return manifest, per_cell
