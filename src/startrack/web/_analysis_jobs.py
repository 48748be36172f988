"""Analysis jobs: one post-processing analysis over result sets of finished solve jobs.

A request names the analysis, its parameters and the result sets, each either a batch
(``{"batch": id}``) or a list of jobs (``{"name": ..., "jobs": [id, ...]}``). It is checked when it
is submitted (:func:`validate_request`: the analysis exists, the number of sets is within its
``min_sets``..``max_sets``, the parameters pass :func:`startrack.analysis.postprocess.check_params`,
every job exists, is a solve job and has finished) and runs in a worker like a solve job
(:func:`run_analysis_job`): each job's :class:`~startrack.analysis._records.ImageRecord` is rebuilt
from its folder (:func:`startrack.web._records.job_record`), then
:func:`startrack.analysis.postprocess.run_analysis` makes the figure and tables, written as
``<analysis>.png`` and ``<analysis>_<table>.csv`` beside ``result.json`` (title, summary, files).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

from ..errors import InvalidInputError
from ._batches import BatchStore, clean_name
from ._jobs import TERMINAL, JobStore, UnknownJobError, now_iso, read_json, update_state, write_json
from ._refusals import Refusal

MAX_SETS = 6
MAX_JOBS_PER_SET = 500


def _analysis_info(name: Any):
    from ..analysis.postprocess import ANALYSES

    if not isinstance(name, str) or name not in ANALYSES:
        raise Refusal(422, f"unknown analysis {str(name)[:40]!r}; valid analyses: {', '.join(ANALYSES)}", "analysis")
    return ANALYSES[name]


def validate_request(body: Any, jobs: JobStore, batches: BatchStore) -> dict[str, Any]:
    """The checked request (analysis, params, sets as names and job ids); a Refusal otherwise."""
    from ..analysis.postprocess import check_params

    if not isinstance(body, dict):
        raise Refusal(422, "the body must be a JSON object with analysis, sets and params", "body")
    unknown = sorted(set(body) - {"analysis", "sets", "params"})
    if unknown:
        raise Refusal(422, f"unknown key {unknown[0]!r}; valid keys: analysis, sets, params", unknown[0])
    info = _analysis_info(body.get("analysis"))
    sets = body.get("sets")
    if not isinstance(sets, list) or not info.min_sets <= len(sets) <= min(info.max_sets, MAX_SETS):
        n = f"{info.min_sets}" if info.min_sets == info.max_sets else f"{info.min_sets} to {info.max_sets}"
        got = len(sets) if isinstance(sets, list) else repr(sets)
        raise Refusal(422, f"{info.name} takes {n} result set(s), got {got}", "sets")
    try:
        params = check_params(info, body.get("params") or {})
    except InvalidInputError as exc:
        raise Refusal(422, str(exc), "params") from None
    checked = [_set(i, s, jobs, batches) for i, s in enumerate(sets)]
    names = [s["name"] for s in checked]
    if len(set(names)) != len(names):
        for i, s in enumerate(checked):
            s["name"] = f"{i + 1}: {s['name']}"
    return {"analysis": info.name, "params": params, "sets": checked}


def _set(index: int, entry: Any, jobs: JobStore, batches: BatchStore) -> dict[str, Any]:
    field = f"sets[{index}]"
    if not isinstance(entry, dict):
        raise Refusal(422, "a result set is {\"batch\": id} or {\"name\": ..., \"jobs\": [id, ...]}", field)
    if "batch" in entry:
        batch = batches.get(entry["batch"])
        name, ids = batch["name"], batch["jobs"]
    else:
        if not isinstance(entry.get("name", ""), str | None):
            raise Refusal(422, f"name must be text, got {entry['name']!r}", f"{field}.name")
        ids, name = entry.get("jobs"), clean_name(entry.get("name")) or f"set {index + 1}"
        if not isinstance(ids, list) or not 1 <= len(ids) <= MAX_JOBS_PER_SET:
            raise Refusal(422, f"jobs must be a list of 1 to {MAX_JOBS_PER_SET} job ids", f"{field}.jobs")
    for job_id in ids:
        _check_job(job_id, jobs, field)
    return {"name": name, "jobs": list(ids)}


def _check_job(job_id: Any, jobs: JobStore, field: str) -> None:
    try:
        meta, state = jobs.meta(job_id), jobs.state(job_id)["state"]
    except UnknownJobError:
        raise Refusal(404, f"{field}: no job {str(job_id)[:40]!r}") from None
    if meta["kind"] != "solve":
        raise Refusal(422, f"{field}: job {job_id} is an analysis, not a solve job", field)
    if state not in TERMINAL:
        raise Refusal(409, f"{field}: job {job_id} is still {state}; analyse finished jobs")


def run_analysis_job(jobs_dir: Path, folder: Path) -> None:
    """Run the analysis job in ``folder`` (module docstring) to its end state."""
    from ..analysis.postprocess import ResultSet, run_analysis

    meta = read_json(folder / "job.json")
    request, times = meta["analysis"], {}
    update_state(folder, stage="records", progress=0.05)
    t0 = time.perf_counter()
    sets, left_out = [], []
    for entry in request["sets"]:
        records = []
        for job_id in entry["jobs"]:
            try:
                records.append(_record(jobs_dir / job_id))
            except FileNotFoundError:
                left_out.append(job_id)
        sets.append(ResultSet(entry["name"], tuple(records)))
    times["records"] = time.perf_counter() - t0
    update_state(folder, stage="analyse", progress=0.2, times_s=times)
    t0 = time.perf_counter()
    result = run_analysis(request["analysis"], sets, request["params"])
    times["analyse"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    written = [p.name for p in result.write(folder)]
    times["write"] = time.perf_counter() - t0
    write_json(folder / "result.json", {"analysis": result.name, "title": result.title,
                                        "summary": {k: _plain(v) for k, v in result.summary.items()},
                                        "figure": written[0], "tables": written[1:], "left_out_jobs": left_out,
                                        "times_s": times})
    update_state(folder, state="done", stage=None, progress=1.0, times_s=times, finished=now_iso())


def _record(folder: Path):
    from ._records import job_record

    return job_record(folder)


def _plain(value: Any) -> Any:
    """A summary value as JSON: numbers (None when not finite), text otherwise."""
    if isinstance(value, str) or value is None:
        return value
    try:
        number = float(value)
    except (TypeError, ValueError):
        return str(value)
    if not math.isfinite(number):
        return None
    return int(value) if isinstance(value, int) and not isinstance(value, bool) else number
