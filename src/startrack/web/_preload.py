"""Imported once by the worker pool's fork server, before it forks any worker.

The pool (:mod:`._runner`) starts its workers with multiprocessing's ``forkserver`` method: a
clean interpreter (started fresh, not forked from the server and its threads) imports this
module, then forks one child per worker. Importing it imports the job's modules and loads the
catalog and the default pattern database (:func:`.worker.prewarm`), so every worker, the first
ones and each that replaces a killed or crashed worker, starts warm in milliseconds and shares
those pages with its siblings instead of loading them again. If this fails, the fork server goes
on and each worker warms itself when it starts.
"""

from __future__ import annotations

from ._worker import prewarm

try:
    prewarm()
except Exception:  # the workers warm themselves (worker_main) and report any problem there
    pass
