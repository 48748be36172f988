"""The body of one worker process: wait for a job id on the pipe, run the job, say it finished.

A worker is started with the ``spawn`` method (a fresh interpreter: no state shared with the
server's threads) by :class:`startrack.web._runner.WorkerPool`. It loads the catalog and the
default pattern database first (``prewarm``), then sends ``("ready", pid)``; for each
``("run", job_id)`` it runs the job and sends ``("finished", job_id)``. Everything a job reports
(stage, progress, result, error) goes through the job's ``state.json``. An exception inside a
job ends it as failed with the exception's message; a crash of the whole process is noticed by
the pool. The worker exits when the pipe closes (the server stopped).
"""

from __future__ import annotations

import os
import signal
from multiprocessing.connection import Connection
from pathlib import Path

from ..errors import StartrackError
from ._jobs import now_iso, read_json, update_state


def prewarm() -> None:
    """Import the job's modules, load the catalog and the default pattern database, solve one
    star list (the compiled search and fit are loaded on their first call) and draw one small
    figure (matplotlib's font cache), so that the first job costs what the others do."""
    import io

    from ..identify import DEFAULT_FOV_RANGE_DEG, database_settings_for, load_database
    from ..plotting import new_figure
    from ..warm_up import solve_catalog_stars
    from . import _analysis_jobs as analysis_jobs  # noqa: F401 (imported for their import time)
    from . import _pipeline as pipeline  # noqa: F401 (imported for their import time)

    load_database(database_settings_for(DEFAULT_FOV_RANGE_DEG))
    solve_catalog_stars()  # with the default FOV search, as jobs without options run
    fig = new_figure(figsize=(1, 1))
    fig.add_subplot().set_title("warm-up")
    fig.savefig(io.BytesIO(), format="png")


def run_job(jobs_dir: Path, job_id: str) -> None:
    """Run one job to its end state (done or failed), whatever happens inside it."""
    folder = jobs_dir / job_id
    try:
        kind = read_json(folder / "job.json")["kind"]
        if kind == "analysis":
            from ._analysis_jobs import run_analysis_job

            run_analysis_job(jobs_dir, folder)
        else:
            from ._pipeline import run_solve_job

            run_solve_job(folder)
    except (StartrackError, ValueError, OSError, KeyError, TypeError) as exc:
        update_state(folder, state="failed", error=_one_line(exc, folder), finished=now_iso())
    except Exception as exc:  # a bug must end the job, not the worker
        update_state(folder, state="failed",
                     error=f"internal error: {type(exc).__name__}: {_one_line(exc, folder)}", finished=now_iso())


def _one_line(exc: BaseException, folder: Path) -> str:
    """The exception's message on one line, the server's own folder left out of the paths it
    names (``input.png: PNG file is truncated``, not the job folder's absolute path)."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text.replace(f"{folder}{os.sep}", "")


def worker_main(conn: Connection, jobs_dir: str, warm: bool) -> None:
    """Entry point of a worker process (see the module docstring)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C stops the server, which stops us
    if warm:
        prewarm()
    conn.send(("ready", os.getpid()))
    while True:
        try:
            kind, job_id = conn.recv()
        except (EOFError, OSError):
            return
        if kind != "run":
            return
        run_job(Path(jobs_dir), job_id)
        try:
            conn.send(("finished", job_id))
        except (BrokenPipeError, OSError):
            return
