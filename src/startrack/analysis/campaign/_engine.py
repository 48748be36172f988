"""Where the chunks run: a Dask distributed cluster (local by default, or a scheduler's), or this
process (synchronous mode, for debugging).

On Dask, every worker is warmed before its first chunk (a ``WarmUp`` worker plugin runs one
throwaway trial of every cell, so the catalog, the pattern databases and the compiled kernels are
loaded once per worker, including workers that join later; :mod:`._warm_plugin`). The spec (a few
kilobytes) goes with every chunk: a scattered copy would be lost with the worker holding it.
Chunks are gathered as they finish, each handed to ``on_chunk`` (which writes its part). A chunk
whose worker dies is split into single trials and sent again; a single trial whose worker dies
three times becomes a ``LOST`` row with the error, never a lost campaign; so do the trials still
waiting when no worker has been connected for :data:`NO_WORKERS_S` (never a hung campaign).
"""

from __future__ import annotations

import contextlib
import logging
import os
import threading
import time
import traceback
from collections.abc import Callable, Iterator
from typing import Any

import pyarrow as pa

from ...errors import InvalidInputError
from ._spec import CampaignSpec
from ._trials import Chunk, lost_table, run_chunk
from .levels import warm

ChunkDone = Callable[[Chunk, pa.Table], None]

LOCAL_CLUSTER_CONFIG = {
    # a local worker that dies was killed by its trial: no blind retries, the chunk is split into
    # single trials instead (run_dask)
    "distributed.scheduler.allowed-failures": 0,
    # a task goes to a worker only when its thread is free, so none waits behind a trial that
    # kills the worker
    "distributed.scheduler.worker-saturation": 1.0,
    # one thread per library in each single-threaded worker, but not Dask's MALLOC_TRIM_THRESHOLD_
    # (see warm_plugin.undo_malloc_trim, which repairs it on workers started by others)
    "distributed.nanny.pre-spawn-environ": {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1},
    # the statistical profiler samples the trial thread's stack every 10 ms, taking the GIL from
    # it; campaigns time their own trials
    "distributed.worker.profile.enabled": False,
    # the event loop's latency probe wakes every 20 ms by default and takes the GIL from the trial
    # thread each time: star-list trials on one worker took 1.33x their in-process time (measured)
    "distributed.admin.tick.interval": "1000ms",
}
"""Dask settings of the local clusters this module starts."""

SINGLE_TRIES = 3
"""A single trial whose worker dies this many times is a ``LOST`` row."""
Progress = Callable[[int, int], None]


def warm_cells(spec: CampaignSpec) -> None:
    """Run one throwaway trial per distinct warm-up key (the cell's parameters unless the level
    says otherwise, :mod:`.levels`) in this process."""
    level = spec.level_def
    seen: list[Any] = []
    for cell in spec.cells():
        key = cell.params if level.warm_key is None else level.warm_key(cell.params)
        if key not in seen:
            seen.append(key)
            with contextlib.suppress(Exception):  # a cell that raises will say so in its own rows
                warm(level, cell.params)


def run_sync(spec: CampaignSpec, chunks: list[Chunk], on_chunk: ChunkDone,
             progress: Progress | None = None) -> dict[str, float]:
    """Run the chunks one after the other in this process; returns the seconds spent warming
    (``warm_s``) and running the chunks (``compute_s``)."""
    t0 = time.perf_counter()
    warm_cells(spec)
    t1 = time.perf_counter()
    total, done = sum(c.size for c in chunks), 0
    for chunk in chunks:
        on_chunk(chunk, run_chunk(spec, chunk))
        done += chunk.size
        if progress is not None:
            progress(done, total)
    return {"warm_s": t1 - t0, "compute_s": time.perf_counter() - t1}


@contextlib.contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None) -> Iterator[Any]:
    """A Dask client: on ``scheduler`` (``tcp://HOST:PORT``) or on a new local cluster of
    ``workers`` single-threaded worker processes (default: one per core), closed afterwards."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InvalidInputError("campaigns need Dask: pip install 'startrack[campaign]'") from None
    if scheduler is not None:
        with _scheduler_client(Client, scheduler) as client:
            yield client
        return
    n = workers if workers is not None else (os.cpu_count() or 1)
    if n < 1:
        raise InvalidInputError(f"--workers must be at least 1, got {n}")
    import dask

    with (dask.config.set(LOCAL_CLUSTER_CONFIG),
          LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                       silence_logs=logging.ERROR) as cluster, Client(cluster) as client):
        yield client
        _settled(client, n)


SETTLE_S = 15.0
"""How long a local cluster may take, at the end of a run, to have all its workers up again before
it is closed (:func:`_settled`)."""


def _settled(client: Any, n: int) -> None:
    """Wait, at most :data:`SETTLE_S`, for the local cluster's ``n`` workers to be up: a worker that
    died in the run (a trial that killed its process) is being started again by its nanny, and a
    cluster closed in the middle of that start fails inside Dask ("can only join a started
    process", once in CI) after every result was stored. Past the wait the cluster is closed as it is."""
    try:
        client.wait_for_workers(n, timeout=SETTLE_S)
    except TimeoutError:
        pass


CONNECT_S = 20.0
"""How long a connection to a ``--scheduler`` may take (Dask's own timeout, and the bound on a
peer that accepts the connection but never answers as a scheduler)."""


def _scheduler_client(client_class: Any, address: str) -> Any:
    """A Dask ``Client`` on the scheduler at ``address``; InvalidInputError naming the address
    when it is not one.

    A web server there (the dashboard's port given by mistake) answers Dask's handshake with
    ``HTTP/1.1 ...``, whose bytes Dask reads as a frame length of exabytes (a MemoryError), or
    keeps the connection open without a reply past Dask's own timeout; so the connection is made
    in a daemon thread and waited for :data:`CONNECT_S` (plus a margin) at most; a client that
    connects after that is closed by the thread.
    """
    outcome: dict[str, Any] = {}
    lock = threading.Lock()

    def connect() -> None:
        try:
            client = client_class(address, timeout=f"{CONNECT_S:g}s")
        except BaseException as exc:  # noqa: BLE001  # handed to the caller below
            outcome["error"] = exc
            return
        with lock:
            if not outcome.get("abandoned"):
                outcome["client"] = client
                return
        client.close()  # connected after the caller gave up: nobody else would close it

    thread = threading.Thread(target=connect, name="startrack-scheduler-connect", daemon=True)
    thread.start()
    thread.join(CONNECT_S + 5.0)
    with lock:
        if "client" in outcome:
            return outcome["client"]
        outcome["abandoned"] = True
    error = outcome.get("error")
    if isinstance(error, KeyboardInterrupt | SystemExit):
        raise error
    detail = "no answer" if error is None else " ".join(f"{type(error).__name__}: {error}".split())[:200]
    raise InvalidInputError(f"--scheduler {address}: no Dask scheduler answered there within {CONNECT_S:g} s "
                            f"({detail}); give the scheduler's own address (tcp://HOST:8786 by default), "
                            "not its dashboard's") from None


NO_WORKERS_S = 120.0
"""With chunks pending and no worker connected for this long, the rest are ``LOST`` rows (local
workers whose nannies could not restart them, a cluster whose workers all left)."""
POLL_S = 5.0
"""How often the watchdog asks the scheduler whether any worker is left."""


def run_dask(client: Any, spec: CampaignSpec, chunks: list[Chunk], on_chunk: ChunkDone,
             progress: Progress | None = None) -> dict[str, float]:
    """Run the chunks on ``client``'s workers (see the module docstring); returns the seconds
    spent warming the workers (``warm_s``) and from the first submission to the last result
    (``compute_s``)."""
    from distributed import as_completed

    from ._warm_plugin import WarmUp

    t0 = time.perf_counter()
    client.register_plugin(WarmUp(spec), name=f"startrack-warm-{spec.name}")
    t1 = time.perf_counter()
    pending = {client.submit(run_chunk, spec, chunk, pure=False): (chunk, 0) for chunk in chunks}
    total, done = sum(c.size for c in chunks), 0
    queue = as_completed(list(pending))
    with _Watchdog(client, pending) as watchdog:
        for future in queue:
            chunk, tries = watchdog.pop(future)
            if watchdog.fired.is_set():
                table = lost_table(spec, chunk, watchdog.reason)
            else:
                table = _table_or_retry(client, spec, future, chunk, tries, watchdog, queue)
            if table is None:
                continue
            on_chunk(chunk, table)
            done += chunk.size
            if progress is not None:
                progress(done, total)
    return {"warm_s": t1 - t0, "compute_s": time.perf_counter() - t1}


class _Watchdog:
    """The pending futures (future -> (chunk, tries)), shared with a thread that cancels them all
    once no worker has been connected for :data:`NO_WORKERS_S` (``fired`` is then set, and each
    cancelled chunk becomes ``LOST`` rows with :attr:`reason`)."""

    def __init__(self, client: Any, pending: dict[Any, tuple[Chunk, int]]):
        self.client, self.pending, self.lock = client, pending, threading.Lock()
        self.fired, self.stop = threading.Event(), threading.Event()
        self.reason = f"no Dask worker was connected for {NO_WORKERS_S:g} s while this trial waited"
        self.thread = threading.Thread(target=self._watch, name="startrack-campaign-watchdog", daemon=True)

    def __enter__(self) -> _Watchdog:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join()

    def pop(self, future: Any) -> tuple[Chunk, int]:
        with self.lock:
            return self.pending.pop(future)

    def add(self, future: Any, entry: tuple[Chunk, int]) -> None:
        with self.lock:
            self.pending[future] = entry
            if self.fired.is_set():  # submitted as the watchdog gave up: it will not wait either
                self.client.cancel([future])

    def _watch(self) -> None:
        idle_since = None
        while not self.stop.wait(POLL_S):
            if self._has_workers():
                idle_since = None
                continue
            idle_since = idle_since or time.perf_counter()
            if time.perf_counter() - idle_since >= NO_WORKERS_S:
                with self.lock:
                    self.fired.set()
                    futures = list(self.pending)
                self.client.cancel(futures)
                return

    def _has_workers(self) -> bool:
        try:
            return bool(self.client.scheduler_info(n_workers=-1).get("workers"))
        except Exception:  # the scheduler itself is gone: as good as no workers
            return False


def _table_or_retry(client: Any, spec: CampaignSpec, future: Any, chunk: Chunk, tries: int,
                    watchdog: _Watchdog, queue: Any) -> pa.Table | None:
    """The chunk's table; or, when its worker died, None with its retries submitted (added to the
    watchdog's futures and the ``as_completed`` queue); ``LOST`` rows once a single trial has
    failed :data:`SINGLE_TRIES` times."""
    try:
        table = future.result()
    except Exception:  # the worker died (or the chunk could not be sent): retry trial by trial
        retries = _retries(chunk, tries)
        for single, attempt in retries:
            retry = client.submit(run_chunk, spec, single, pure=False)
            watchdog.add(retry, (single, attempt))
            queue.add(retry)
        if retries:
            return None
        table = lost_table(spec, chunk, traceback.format_exc())
    future.release()
    return table


def _retries(chunk: Chunk, tries: int) -> list[tuple[Chunk, int]]:
    """What to send again after ``chunk`` failed: each of its trials alone, or, for a single
    trial, itself until it has failed :data:`SINGLE_TRIES` times (a trial waiting on a worker
    that another trial killed fails with it, through no fault of its own)."""
    if chunk.size > 1:
        return [(Chunk(chunk.cell, k, k + 1), 0) for k in range(chunk.start, chunk.stop)]
    return [(chunk, tries + 1)] if tries + 1 < SINGLE_TRIES else []


def workers_info(client: Any) -> dict[str, Any]:
    """Hosts and number of the client's workers (for the manifest)."""
    info = client.scheduler_info(n_workers=-1).get("workers", {})
    hosts = sorted({w.get("host", addr) for addr, w in info.items()})
    return {"workers": len(info), "hosts": hosts, "scheduler": client.scheduler.address}
