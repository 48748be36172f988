"""startrack warm-up: compile the solver's kernels and build the default pattern database now.

After an install (or an upgrade that changed a kernel) numba compiles startrack's compiled loops
once and caches them (see :mod:`startrack.numba_cache`); the pattern database is built once per
field-of-view range and cached (:mod:`startrack.identify._database`). Run this at set-up time so
that no later command waits for either. The solving commands also warm up before their first
solve (:func:`warm_up`): a star list of catalog stars is solved, so that compiling, or loading
the compiled code from the cache, never falls inside a reported solve time, and when numba does
compile they say so first ("compiling ... (one time ...)") on standard error.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from collections.abc import Iterator

from numpy.typing import NDArray

from ..camera import Camera
from ..warm_up import solve_catalog_stars
from ._common import exit_status_epilog
from ._parser import CommandParser
from ._process_gc import collection_paused, no_collection_at_exit

COMPILE_ESTIMATE_S = 60
"""What compiling every kernel takes on the 2-core reference machine, for the message: 22-44 s
measured by ``benchmarks/startup_benchmark.py --cold`` with the machine shared (load 3-4) before
the detector's per-region and uncertainty loops were compiled, 59 s on 2026-12-06 after (the
same machine then ran the earlier code's compile in 48 s)."""

EXIT_STATUS = exit_status_epilog("0 ready (the database built or found, the kernels compiled or loaded); 2 misuse (a "
                                 "bad option), with one line 'startrack warm-up: error: ...' on standard error;")
"""The exit status paragraph of ``startrack warm-up --help``."""


class _CompileNotice:
    """A numba event listener that prints one line when the first compilation starts."""

    def __init__(self) -> None:
        from numba.core import event

        class Listener(event.Listener):
            def on_start(inner, ev) -> None:  # noqa: N805 - the outer object holds the state
                self.started()

            def on_end(inner, ev) -> None:  # noqa: N805
                pass

        self.listener = Listener()
        self.t0: float | None = None

    def started(self) -> None:
        if self.t0 is None:
            self.t0 = time.perf_counter()
            when = "one time after an install" if _keeps_compiled_code() else "every run: no cache folder to keep it"
            sys.stderr.write(f"compiling startrack's solver kernels ({when}, about {COMPILE_ESTIMATE_S} s) ...\n")
            sys.stderr.flush()

    def finished(self) -> None:
        if self.t0 is not None:
            kept = "cached for later runs" if _keeps_compiled_code() else "not cached (see the warning above)"
            sys.stderr.write(f"compiled in {time.perf_counter() - self.t0:.1f} s; {kept}\n")
            sys.stderr.flush()


def _keeps_compiled_code() -> bool:
    """Whether this process's compiled code is kept for later runs (its cache folder, checked
    once a process, can be written: :func:`startrack.numba_cache.configured_dir`)."""
    from .. import numba_cache

    numba_cache.configured_dir()
    return numba_cache.keeps_compiled_code()


def warm_up(fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
            camera: Camera | None = None, epoch: float | None = None, image: NDArray | None = None,
            every_detection: bool = False) -> None:
    """Load (or, the first time, compile with a message on stderr) the solver's compiled kernels
    by solving catalog stars with these field-of-view options (checked, as the solvers take them)
    at the catalog ``epoch`` (Julian year; default J2000.0) of the solve to come, whose catalog
    stars are then prepared too; and the detector's for frames like ``image`` (its dtype and
    channels), or for every frame type with ``every_detection``."""
    with _announced_compiling():
        solve_catalog_stars(fov_deg, fov_range_deg, camera, epoch=epoch)
        _detection(image, every_detection)


def warm_up_detection(image: NDArray | None = None, every_detection: bool = False) -> None:
    """The detector's part of :func:`warm_up` alone (for ``startrack detect``)."""
    with _announced_compiling():
        _detection(image, every_detection)


@contextlib.contextmanager
def _announced_compiling() -> Iterator[None]:
    """A block whose numba compilations are announced on stderr (once), with the collector paused."""
    from numba.core import event

    no_collection_at_exit()
    notice = _CompileNotice()
    with event.install_listener("numba:compile", notice.listener), collection_paused():
        yield
    notice.finished()


def _detection(image: NDArray | None, every_detection: bool) -> None:
    from ..detect import warm_up_detect

    if every_detection:
        from ..io import warm_up_png16

        warm_up_detect()
        warm_up_png16()
    elif image is not None:
        warm_up_detect((image.dtype,), channels=image.shape[2] if image.ndim == 3 else 1)


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack warm-up", description=__doc__, epilog=EXIT_STATUS,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fov-range-deg", type=float, nargs=2, metavar=("LO", "HI"),
                        help="also build the database for this range of fields of view, deg "
                             "(default: the ranges a solve with no field of view searches, 3-100 deg and, "
                             "when that finds nothing in an image, 90-150 deg)")
    return parser


def main(argv: list[str]) -> int:
    from ._common import fov_kwargs
    from ._progress import ensure_database_for

    args = _parser().parse_args(argv)
    args.fov_deg = args.camera = None
    options = fov_kwargs(args)
    t0 = time.perf_counter()
    ensure_database_for(**options)
    if args.fov_range_deg is None:  # the ultra-wide search after a default one that found nothing
        from ..solve import WIDE_RETRY_FOV_RANGE_DEG

        ensure_database_for(fov_range_deg=WIDE_RETRY_FOV_RANGE_DEG)
    warm_up(**options, every_detection=True)
    print(f"startrack is ready: database and compiled kernels loaded in {time.perf_counter() - t0:.1f} s")
    return 0
