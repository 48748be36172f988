"""The bounded pool of worker processes that runs the jobs: queue, time limit, cancellation, crashes.

Each worker is a long-lived process (:mod:`._worker`) that keeps its catalog and pattern database
loaded between jobs, so that a sub-second solve takes a sub-second. Workers are forked by
multiprocessing's fork server, a fresh interpreter (not a fork of the server and its threads)
that has imported the job's modules and loaded the catalog and default database once
(:mod:`._preload`): a worker that replaces a killed one is ready at once. A dispatcher thread in
the server wakes every :data:`TICK_S` and, under one lock:

- hands the oldest queued job to each idle, ready worker (the job becomes ``running``);
- ends a job whose worker said it finished (the worker wrote its end state);
- kills the worker of a job that was cancelled (``cancelled``) or that ran past the time limit
  (``failed``, "timed out after N s"), and of a job whose worker died on its own (``failed``,
  "the worker process stopped unexpectedly ..."); a fresh worker replaces every killed or dead
  one, so the pool never shrinks and no job stays ``running`` for ever.

The queue holds at most ``max_queued`` jobs (:class:`QueueFullError`, the API's 429). A killed
worker may have been writing a file: every job file is written atomically, so what is left is
either the old file or none.
"""

from __future__ import annotations

import multiprocessing as mp
import threading
import time
from collections import deque
from dataclasses import dataclass
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from typing import Any

from ._jobs import TERMINAL, JobStore, UnknownJobError, now_iso

TICK_S = 0.05
JOIN_S = 5.0


class QueueFullError(RuntimeError):
    """The queue already holds ``max_queued`` jobs."""


@dataclass
class _Worker:
    process: BaseProcess
    conn: Connection
    ready: bool = False
    job_id: str | None = None
    started_s: float = 0.0
    limit_s: float = 0.0


class WorkerPool:
    """``n_workers`` worker processes running the jobs of ``store`` (see the module docstring).

    Parameters
    ----------
    store : JobStore
    n_workers : int
    time_limit_s : float
        Wall-clock limit of one job, counted from the moment a ready worker takes it (a job's
        ``time_limit_s`` option may shorten it).
    max_queued : int
        Jobs that may wait.
    prewarm : bool
        Workers load the catalog and the default pattern database before they say they are ready.
    """

    def __init__(self, store: JobStore, n_workers: int, time_limit_s: float, max_queued: int,
                 prewarm: bool = True):
        self.store, self.n_workers = store, n_workers
        self.time_limit_s, self.max_queued, self.prewarm = time_limit_s, max_queued, prewarm
        self._ctx = mp.get_context("forkserver")
        if prewarm:
            self._ctx.set_forkserver_preload(["startrack.web._preload"])
        self._lock = threading.RLock()
        self._queue: deque[str] = deque()
        self._cancel: set[str] = set()
        self._workers: list[_Worker] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.restarts = 0

    # --- life cycle ---------------------------------------------------------------------------
    def start(self, queued: list[str] | tuple[str, ...] = ()) -> None:
        """Start the dispatcher, which starts the workers; ``queued`` are jobs left waiting by an
        earlier server. Returns at once: the server answers while the first workers warm up (the
        fork server's preload takes seconds), and jobs wait in the queue until a worker is ready."""
        with self._lock:
            self._queue.extend(queued)
        self._thread = threading.Thread(target=self._loop, name="startrack-dispatcher", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the dispatcher and the workers; jobs still running end as failed (server stopped)."""
        self._stop.set()
        if self._thread is not None:  # a dispatcher still starting the workers kills them itself
            self._thread.join(JOIN_S if self._workers else TICK_S)
        with self._lock:
            for worker in self._workers:
                if worker.job_id is not None:
                    self._end(worker.job_id, "failed", "the server stopped while this job was running")
                self._kill(worker)
            self._workers = []

    def _spawn(self) -> _Worker:
        from ._worker import worker_main

        parent, child = self._ctx.Pipe()
        process = self._ctx.Process(target=worker_main, args=(child, str(self.store.root), self.prewarm),
                                    name="startrack-worker", daemon=True)
        process.start()
        child.close()
        return _Worker(process, parent)

    def _kill(self, worker: _Worker) -> None:
        if worker.process.is_alive():
            worker.process.kill()
        worker.process.join(JOIN_S)
        worker.conn.close()

    def _replace(self, worker: _Worker) -> None:
        self._kill(worker)
        self._workers[self._workers.index(worker)] = self._spawn()
        self.restarts += 1

    # --- requests from the API ----------------------------------------------------------------
    def has_room(self) -> bool:
        """True while another job may be queued."""
        with self._lock:
            return len(self._queue) < self.max_queued

    def submit(self, job_id: str) -> None:
        """Queue a job (already created in the store); QueueFullError when the queue is full."""
        with self._lock:
            if len(self._queue) >= self.max_queued:
                raise QueueFullError(f"the queue is full ({self.max_queued} jobs waiting); try again later")
            self._queue.append(job_id)

    def cancel(self, job_id: str) -> str:
        """Cancel a queued or running job; returns its state afterwards (a finished job's is unchanged)."""
        with self._lock:
            if job_id in self._queue:
                self._queue.remove(job_id)
                self._end(job_id, "cancelled", None)
                return "cancelled"
            worker = next((w for w in self._workers if w.job_id == job_id), None)
            if worker is not None:
                self._cancel.add(job_id)
                self._check(worker)
            return self.store.state(job_id)["state"]

    def info(self) -> dict[str, Any]:
        """Workers (pid, ready, job), queue length and restarts, for the status endpoint."""
        with self._lock:
            return {"workers": [{"pid": w.process.pid, "ready": w.ready, "job": w.job_id} for w in self._workers],
                    "starting": len(self._workers) < self.n_workers, "queued": len(self._queue),
                    "max_queued": self.max_queued,
                    "time_limit_s": self.time_limit_s, "restarts": self.restarts}

    def queue_position(self, job_id: str) -> int | None:
        """1 for the next job to run, None when the job is not waiting."""
        with self._lock:
            return self._queue.index(job_id) + 1 if job_id in self._queue else None

    # --- the dispatcher -----------------------------------------------------------------------
    def _loop(self) -> None:
        started = [self._spawn() for _ in range(self.n_workers)]  # outside the lock: the first one
        with self._lock:                                           # waits for the fork server's preload
            if self._stop.is_set():  # the server stopped meanwhile
                for worker in started:
                    self._kill(worker)
                return
            self._workers = started
        while not self._stop.wait(TICK_S):
            with self._lock:
                for worker in list(self._workers):
                    self._check(worker)
                for worker in self._workers:
                    if worker.ready and worker.job_id is None and self._queue:
                        self._dispatch(worker, self._queue.popleft())

    def _dispatch(self, worker: _Worker, job_id: str) -> None:
        try:
            asked = (self.store.meta(job_id).get("options") or {}).get("time_limit_s")
            self.store.set_state(job_id, state="running", stage=None, started=now_iso())
        except UnknownJobError:  # deleted while it waited
            return
        worker.limit_s = self.time_limit_s if asked is None else min(float(asked), self.time_limit_s)
        worker.job_id, worker.started_s = job_id, time.monotonic()
        worker.conn.send(("run", job_id))

    def _check(self, worker: _Worker) -> None:
        """Read the worker's messages; end its job if it finished, was cancelled, timed out or died."""
        try:
            while worker.conn.poll():
                kind, value = worker.conn.recv()
                if kind == "ready":
                    worker.ready = True
                elif kind == "finished" and value == worker.job_id:
                    worker.job_id = None
        except (EOFError, OSError):
            pass
        job_id = worker.job_id
        if not worker.process.is_alive():
            code = worker.process.exitcode
            if job_id is not None:
                self._end(job_id, "failed", f"the worker process stopped unexpectedly (exit code {code}); "
                                            "the server started a new one")
            self._replace(worker)
        elif job_id is not None and job_id in self._cancel:
            self._cancel.discard(job_id)
            self._replace(worker)
            self._end(job_id, "cancelled", None)
        elif job_id is not None and time.monotonic() - worker.started_s > worker.limit_s:
            self._replace(worker)
            self._end(job_id, "failed", f"timed out after {worker.limit_s:g} s")

    def _end(self, job_id: str, state: str, error: str | None) -> None:
        """Set an end state unless the job already reached one (the worker wrote it just before)."""
        try:
            if self.store.state(job_id)["state"] in TERMINAL:
                return
            self.store.set_state(job_id, state=state, error=error, finished=now_iso())
        except UnknownJobError:
            pass
