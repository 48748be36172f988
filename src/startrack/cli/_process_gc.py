"""The garbage collector around the commands' start-up and exit (the CLI's only global state).

A command imports numba, its registries and the compiled kernels: several hundred thousand
objects that live as long as the process. Collecting them as they arrive, and walking them again
in the collections of interpreter shutdown, costs a noticeable part of a short command's wall
time (``benchmarks/startup_benchmark.py`` prints ``startrack solve IMAGE``), so the CLI pauses
the collector while they load and freezes them at exit.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

_EXIT_HOOK: list[bool] = []


@contextlib.contextmanager
def collection_paused() -> Iterator[None]:
    """The garbage collector off inside the block (objects that live as long as the process are
    loaded there), then as it was."""
    import gc

    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def no_collection_at_exit() -> None:
    """Spare the process the garbage collections of interpreter shutdown (once per process).

    ``gc.freeze`` at exit (an atexit hook, so a process that calls the commands in-process, such
    as a test run, is touched only when it ends) moves the long-lived objects to the permanent
    generation; atexit hooks and finalizers of objects freed by reference count still run.
    """
    if not _EXIT_HOOK:
        import atexit
        import gc

        atexit.register(gc.freeze)
        _EXIT_HOOK.append(True)
