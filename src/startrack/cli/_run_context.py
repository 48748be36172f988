"""What every ``startrack`` subcommand runs inside (:func:`command_context`, used by ``cli.main``).

* The files the command reads are protected: no output may replace one
  (:func:`startrack.io._targets.protect_inputs`).
* A ``--max-pixels`` limit set by the command lasts until it returns
  (:func:`startrack.io._limits.max_pixels_limit`).
* SIGTERM raises :class:`Terminated` in the main thread, so that the outputs' ``finally`` blocks
  run (temporary files removed, old files kept) as for Ctrl-C; the exit status is 143.
* A warning is printed as one line ``startrack <cmd>: warning: ...`` (e.g. a cache folder that
  cannot be written), not Python's two-line form with a source line; ERFA's "dubious year" (a
  time past the leap seconds astropy knows) is put in words.
* :func:`memory_message` words a MemoryError (an input or an option asking for more memory than
  the machine has) for the one-line error and exit status 2.
"""

from __future__ import annotations

import signal
import sys
import threading
import warnings
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager

from ..io import max_pixels_limit, protect_inputs


class Terminated(SystemExit):
    """Raised in the main thread when the process receives SIGTERM (exit status 128 + 15)."""

    def __init__(self) -> None:
        super().__init__(128 + signal.SIGTERM)


def _raise_terminated(signum, frame) -> None:
    raise Terminated


@contextmanager
def _sigterm_raises() -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


DUBIOUS_YEAR = ("a time beyond the leap seconds astropy knows (ERFA's \"dubious year\"): its conversion between "
                "UTC and other time scales may be off by the leap seconds to come, a few seconds at most")
"""ERFA's warning for a UTC time past its leap-second table (the future, or before 1960), in words."""


def warning_text(message: Warning | str) -> str:
    """A warning's message on one line, ERFA's "dubious year" put in words (:data:`DUBIOUS_YEAR`)."""
    text = " ".join(str(message).split())
    return DUBIOUS_YEAR if "dubious year" in text else text


@contextmanager
def _one_line_warnings(name: str) -> Iterator[None]:
    with warnings.catch_warnings():
        def show(message, category, filename, lineno, file=None, line=None) -> None:
            print(f"startrack {name}: warning: {warning_text(message)}", file=sys.stderr if file is None else file)

        warnings.showwarning = show
        yield


@contextmanager
def command_context(name: str) -> Iterator[None]:
    """Inputs protected, SIGTERM as an exception, one-line warnings, for the command ``name``; a
    --max-pixels the command applies (:func:`.common.apply_max_pixels_option`) ends with it."""
    with ExitStack() as stack:
        stack.enter_context(protect_inputs())
        stack.enter_context(max_pixels_limit(None))
        stack.enter_context(_sigterm_raises())
        stack.enter_context(_one_line_warnings(name))
        yield


def memory_message(exc: MemoryError) -> str:
    """The one-line error of a MemoryError."""
    detail = " ".join(str(exc).split())
    return ("out of memory" + (f" ({detail})" if detail else "") +
            ": the input or an option needs more memory than is available; use a smaller image or "
            "smaller sizes (see --max-pixels)")
