"""The clocks of the benchmarks that time work in this process (``--clock wall|cpu``).

``cpu`` is the CPU time of the whole process (``time.process_time``, every thread), which leaves
out the time the process waits for a core on a shared machine but not the slow-down of sharing
its caches and memory bandwidth. (``methods.CLOCKS`` times one solving thread, for the
lost-in-space benchmark whose solvers take turns.)
"""

from __future__ import annotations

import argparse
import time

CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}
"""How a piece of work is timed: the wall clock, or the CPU time of the process."""


def clock_name(clock: str) -> str:
    """The words for ``clock`` in a benchmark's output."""
    return "CPU time of the process" if clock == "cpu" else "wall clock"


def add_clock_option(parser: argparse.ArgumentParser) -> None:
    """``--clock wall|cpu`` (default wall)."""
    parser.add_argument("--clock", choices=tuple(CLOCKS), default="wall",
                        help="time by the wall clock or by the CPU time of the process (default wall)")
