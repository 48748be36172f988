"""The job store: one folder per job under ``<data-dir>/jobs/<id>/``, and the job state machine.

A job's folder holds ``job.json`` (what was asked: kind, options, the upload's label and hash,
written once), ``state.json`` (where it is: state, stage, progress, error, per-stage times;
rewritten atomically by the server and by the worker running it) and the result files. The
states::

    queued -> running -> done | failed          (a worker finished it, or it timed out / crashed)
    queued -> cancelled,  running -> cancelled  (DELETE /api/jobs/{id})

A job that was running when the server stopped is marked failed when the next server starts
(:meth:`JobStore.recover`). Ids are 32 random hex digits made by the server; every id that comes
from a request is checked against :data:`JOB_ID` before it is joined to a path, and result file
names are served only when they are in the folder's own listing (:meth:`JobStore.file_path`).
"""

from __future__ import annotations

import json
import re
import secrets
import shutil
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ..io import atomic_path

JOB_ID = re.compile(r"^[0-9a-f]{32}$")
STATES = ("queued", "running", "done", "failed", "cancelled")
TERMINAL = frozenset({"done", "failed", "cancelled"})
SOLVE_STAGES = ("read", "detect", "identify", "attitude", "refine", "annotate")
"""The stages of a solve job (:mod:`._pipeline`)."""
ANALYSIS_STAGES = ("records", "analyse", "write")
"""The stages of an analysis job (:mod:`._analysis_jobs`)."""
SAFE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,80}\.(png|json|csv|wcs)$")
"""Names of result files that may be served (a job's own files; nothing else is looked up)."""
INTERNAL = frozenset({"job.json", "state.json"})
RESTART_REASON = "the server stopped while this job was running"


class UnknownJobError(LookupError):
    """No job (or batch) with this id: a malformed id or one that does not exist."""


def new_id() -> str:
    """A fresh random id: 32 hex digits (128 bits), never derived from anything a client sent."""
    return secrets.token_hex(16)


def check_id(text: str, what: str = "job") -> str:
    """``text`` if it is a well-formed id; else UnknownJobError (before any path is built)."""
    if not isinstance(text, str) or not JOB_ID.match(text):
        raise UnknownJobError(f"no {what} {str(text)[:40]!r}: ids are 32 lowercase hex digits")
    return text


def now_iso() -> str:
    """The current UTC time, ISO 8601 to the second."""
    return datetime.now(UTC).isoformat(timespec="seconds")


def read_json(path: Path) -> dict[str, Any]:
    """A JSON object from ``path`` (written atomically, so never half-written)."""
    return json.loads(path.read_text())


def write_json(path: Path, data: dict[str, Any]) -> None:
    """``data`` as standard JSON (no NaN), atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=1, allow_nan=False))


def update_state(folder: Path, **changes: Any) -> dict[str, Any]:
    """Merge ``changes`` into ``folder/state.json`` (atomically) and return the new state."""
    path = folder / "state.json"
    state = read_json(path) if path.exists() else {}
    state.update(changes, updated=time.time())
    write_json(path, state)
    return state


class JobStore:
    """The jobs under one folder (see the module docstring)."""

    def __init__(self, jobs_dir: Path):
        self.root = Path(jobs_dir)
        self.root.mkdir(parents=True, exist_ok=True)

    def folder(self, job_id: str) -> Path:
        """The folder of an existing job; UnknownJobError for a malformed or unknown id."""
        path = self.root / check_id(job_id)
        if not (path / "job.json").is_file():
            raise UnknownJobError(f"no job {job_id!r}")
        return path

    def create(self, kind: str, meta: dict[str, Any], job_id: str | None = None) -> str:
        """A new queued job of ``kind`` ("solve" or "analysis") with ``meta`` in its job.json.

        ``job_id`` may be one :func:`new_id` made earlier (when the upload was written into the
        folder first, see :meth:`reserve`)."""
        job_id = job_id or new_id()
        folder = self.root / check_id(job_id)
        folder.mkdir(exist_ok=True)
        write_json(folder / "job.json", {"id": job_id, "kind": kind, "created": now_iso(),
                                         "created_s": time.time(), **meta})
        update_state(folder, state="queued", stage=None, progress=0.0, error=None, times_s={})
        return job_id

    def reserve(self) -> tuple[str, Path]:
        """A fresh id and its (empty) folder, for an upload to be written before the job exists."""
        job_id = new_id()
        folder = self.root / job_id
        folder.mkdir()
        return job_id, folder

    def discard(self, folder: Path) -> None:
        """Remove a reserved folder (an upload that was refused)."""
        if folder.parent == self.root and JOB_ID.match(folder.name):
            shutil.rmtree(folder, ignore_errors=True)

    def meta(self, job_id: str) -> dict[str, Any]:
        return read_json(self.folder(job_id) / "job.json")

    def state(self, job_id: str) -> dict[str, Any]:
        return read_json(self.folder(job_id) / "state.json")

    def set_state(self, job_id: str, **changes: Any) -> dict[str, Any]:
        return update_state(self.folder(job_id), **changes)

    def ids(self) -> list[str]:
        """Every job's id, oldest first."""
        found = []
        for path in self.root.iterdir():
            if JOB_ID.match(path.name) and (path / "job.json").is_file() and (path / "state.json").is_file():
                found.append((read_json(path / "job.json").get("created_s", 0.0), path.name))
        return [job_id for _, job_id in sorted(found)]

    def files(self, job_id: str) -> list[str]:
        """The result files a job has written so far (names, sorted)."""
        folder = self.folder(job_id)
        return sorted(p.name for p in folder.iterdir() if p.is_file() and SAFE_NAME.match(p.name)
                      and p.name not in INTERNAL and not p.name.startswith("input."))

    def file_path(self, job_id: str, name: str) -> Path:
        """The path of result file ``name`` of a job; UnknownJobError unless the folder lists it."""
        if not isinstance(name, str) or name not in self.files(job_id):
            raise UnknownJobError(f"job {job_id} has no file {str(name)[:60]!r}")
        return self.folder(job_id) / name

    def delete(self, job_id: str) -> None:
        """Remove a finished job's folder."""
        shutil.rmtree(self.folder(job_id))

    def recover(self) -> list[str]:
        """After a restart: mark the jobs left running as failed; return the queued ones, oldest first."""
        queued = []
        for job_id in self.ids():
            state = self.state(job_id)["state"]
            if state == "running":
                self.set_state(job_id, state="failed", error=RESTART_REASON, finished=now_iso())
            elif state == "queued":
                queued.append(job_id)
        return queued
