"""Run a campaign: check the spec, plan the chunks, execute them, store and report.

>>> from startrack.analysis.campaign import run_campaign       # doctest: +SKIP
>>> trials = run_campaign("fov-noise.toml", "out/fov-noise", workers=2)   # doctest: +SKIP
>>> trials.group_by("cell").aggregate([("correct", "mean")])  # doctest: +SKIP
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path
from typing import Any

import pyarrow as pa

from ...errors import InvalidInputError
from ._engine import Progress, dask_client, run_dask, run_sync, workers_info
from ._folder import FORMAT
from ._provenance import provenance
from ._spec import CampaignSpec, load_spec, parse_spec
from ._store import CampaignStore, open_store, utc_now
from ._trials import Chunk, plan_chunks

CORRECT_DEFINITION = ("solved with the attitude within {tol:g} pixel angles at the image corner: "
                      "sqrt(err_x^2 + err_y^2 + (w err_roll)^2) <= {tol:g} / sqrt(fx fy), "
                      "w = image half-diagonal / focal length (startrack.analysis._scoring)")


def as_spec(spec: CampaignSpec | str | Path) -> CampaignSpec:
    """A checked spec from a spec, a path to a TOML file, or TOML text (containing a newline)."""
    if isinstance(spec, CampaignSpec):
        return spec
    if isinstance(spec, str) and "\n" in spec:
        return parse_spec(spec)
    return load_spec(spec)


def default_chunk_size(spec: CampaignSpec, workers: int) -> int:
    """The level's chunk size, made smaller when that would leave workers idle (at least eight
    chunks per worker when there are enough trials, so the last ones finish close together)."""
    total = spec.trials * len(spec.cells())
    spread = max(1, math.ceil(total / (8 * max(workers, 1))))
    return max(1, min(spec.level_def.chunk_trials, spread, spec.trials))


def _manifest(spec: CampaignSpec, chunk_size: int) -> dict[str, Any]:
    cells = spec.cells()
    manifest = {
        "format": FORMAT, "name": spec.name, "level": spec.level, "mode": spec.mode, "spec": spec.as_dict(),
        "spec_text": spec.text, "swept": spec.swept, "trials_per_cell": spec.trials, "seed": spec.seed,
        "cells": [{"cell": c.index, "label": c.label, "params": _plain(c.params),
                   **({"source": c.source} if c.source is not None else {})} for c in cells],
        "correct": {"tolerance_px": spec.tolerance_px,
                    "definition": CORRECT_DEFINITION.format(tol=spec.tolerance_px)},
        "chunk_size": chunk_size, "started_utc": utc_now(), "finished_utc": None, "runs": [],
    }
    manifest.update(provenance(cells))
    if spec.mode == "budget":
        from ._budget import budget_manifest

        manifest["budget"] = budget_manifest(spec, cells)
    return manifest


def _plain(params: dict[str, Any]) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}


def _executor_info(workers: int | None, scheduler: str | None, sync: bool) -> int:
    if sync and (workers is not None or scheduler is not None):
        raise InvalidInputError("synchronous mode runs in this process: leave out --workers and --scheduler")
    if workers is not None and scheduler is not None:
        raise InvalidInputError("give --workers (a local cluster) or --scheduler (an existing one), not both")
    if workers is not None and workers < 1:
        raise InvalidInputError(f"--workers must be at least 1, got {workers}")
    return 1 if sync else (workers or os.cpu_count() or 1)


def run_campaign(spec: CampaignSpec | str | Path, out: str | Path, *, workers: int | None = None,
                 scheduler: str | None = None, sync: bool = False, chunk_size: int | None = None,
                 resume: bool = False, progress: Progress | None = None, report: bool = True) -> pa.Table:
    """Run a campaign into the folder ``out`` and return its trial table.

    Parameters
    ----------
    spec : CampaignSpec, path or TOML text
    out : path
        Output folder (created): ``manifest.json``, ``trials/``, ``cells.csv``, the report.
    workers : int, optional
        Worker processes of a new local Dask cluster (default: one per core).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://HOST:PORT``) to use instead.
    sync : bool
        Run every trial in this process, without Dask (for debugging).
    chunk_size : int, optional
        Trials per task (default :func:`default_chunk_size`; on ``resume`` the manifest's).
    resume : bool
        Finish a campaign interrupted in ``out``: only the chunks without a part run.
    progress : callable(done, total), optional
        Called as trials finish.
    report : bool
        Write ``cells.csv`` and the report at the end.

    Returns
    -------
    pyarrow.Table
        One row per trial, sorted by cell and trial (``docs/campaigns.md``).

    Raises
    ------
    SpecError, InvalidInputError
        For a bad spec or options, before any work.
    """
    spec = as_spec(spec)
    n_workers = _executor_info(workers, scheduler, sync)
    if chunk_size is not None and chunk_size < 1:  # before the folder is made
        raise InvalidInputError(f"--chunk-size must be at least 1, got {chunk_size}")
    store, manifest = open_store(out, spec, resume=resume)
    fresh = manifest is None
    if manifest is None:
        manifest = _manifest(spec, chunk_size or default_chunk_size(spec, n_workers))
        store.write_manifest(manifest)
    done = store.done_keys()
    chunks = [c for c in plan_chunks(spec.cells(), spec.trials, manifest["chunk_size"]) if c.key not in done]
    try:
        _execute(spec, store, manifest, chunks, workers, scheduler, sync, progress)
    except BaseException:
        if fresh and not store.done_keys():  # nothing ran: leave no campaign behind
            store.discard()
        raise
    if report:
        from ._report import write_report

        write_report(store.out)
    return store.read_trials()


def _execute(spec: CampaignSpec, store: CampaignStore, manifest: dict[str, Any], chunks: list[Chunk],
             workers: int | None, scheduler: str | None, sync: bool, progress: Progress | None) -> None:
    def on_chunk(chunk: Chunk, table: pa.Table) -> None:
        store.write_part(chunk, table)

    t0 = time.perf_counter()
    run = {"started_utc": utc_now(), "chunks": len(chunks)}
    if sync:
        run.update(mode="synchronous", workers=1)
        timings = run_sync(spec, chunks, on_chunk, progress)
    else:
        with dask_client(workers, scheduler) as client:
            run.update(mode="dask", **workers_info(client))
            timings = run_dask(client, spec, chunks, on_chunk, progress)
    run.update({k: round(v, 3) for k, v in timings.items()})
    run.update(finished_utc=utc_now(), wall_s=round(time.perf_counter() - t0, 3))
    manifest["runs"] = [*manifest.get("runs", []), run]
    manifest["finished_utc"] = run["finished_utc"]
    driver = manifest.get("driver_host", "unknown")
    manifest["hosts"] = sorted({h for r in manifest["runs"] for h in r.get("hosts", [driver])})
    manifest["workers"] = run["workers"]
    store.write_manifest(manifest)
