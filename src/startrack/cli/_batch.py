"""Batches of images in one process: ``startrack solve A.jpg B.fits FOLDER`` and ``startrack detect``.

Each image gives one *record* (a JSON-ready dict with at least ``image``, ``status`` and
``reason``), built by the command's function for one image, in this process or in ``--jobs N``
worker processes (forked after the catalog, the pattern database and the compiled kernels are
loaded, so a worker starts warm). The records come back in the order of the inputs and are
written as they arrive: one table line per image (or one JSON object per line with ``--json``),
rows of a CSV file with ``--csv OUT`` (written atomically when the batch ends), a progress bar
on standard error when it is a terminal, and a summary on standard error: how many were done,
and each image that was not, with its status and reason.

A file that cannot be read or used (missing, not an image, too large, an invalid image) is
reported on its line with status ``error`` and the problem; the others go on. So is any other
exception one image raises (a fault of startrack's, named as such with its type), so that one
file does not cost the rest of the batch. Misuse of the command (a bad option, a folder with no
images) stops it before any image, exit status 2.

When standard output closes early (``startrack solve FOLDER --csv out.csv | head -3``), the lines
stop there; with ``--csv OUT`` the batch still goes on and writes OUT, without it the command
stops quietly (exit status 141, as on SIGPIPE).
"""

from __future__ import annotations

import csv
import json
import os
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InvalidInputError, StartrackError, hidden_interruption
from ..io import IMAGE_SUFFIXES, in_name_order

ERROR = "error"
"""Status of an image that could not be read or used (the reason says why)."""

Record = dict[str, Any]


@dataclass(frozen=True)
class BatchSpec:
    """What a command does with a batch.

    Attributes
    ----------
    name : str
        The subcommand (``solve``, ``detect``), for messages.
    process : callable
        ``process(path) -> record`` for one image; picklable (a module-level function or a
        ``functools.partial`` of one) when ``jobs > 1``. Misuse-type errors it raises
        (StartrackError, ValueError, OSError, MemoryError) become an ``error`` record.
    header : str
        First line of the table.
    line : callable
        ``line(record, width) -> str``: the table line of a record, ``width`` the image column's.
    csv_columns : sequence of str
        Columns of ``--csv``.
    csv_rows : callable
        ``csv_rows(record) -> iterable of dicts`` (keys among ``csv_columns``).
    done_statuses : frozenset of str
        Statuses that count as done (exit status 0 when every image has one).
    """

    name: str
    process: Callable[[Path], Record]
    header: str
    line: Callable[[Record, int], str]
    csv_columns: Sequence[str]
    csv_rows: Callable[[Record], Iterable[Record]]
    done_statuses: frozenset[str]


def is_batch(paths: Sequence[str], csv_out: str | None = None) -> bool:
    """True for more than one path, a folder, or a --csv: the batch output; else one image as before."""
    return len(paths) > 1 or csv_out is not None or Path(paths[0]).is_dir()


def expand_inputs(paths: Sequence[str | os.PathLike]) -> list[Path]:
    """The images of ``paths``: each folder's image files (:data:`IMAGE_SUFFIXES`, in name order
    with numbers compared as numbers, :func:`startrack.io.natural_key`; not recursive), other paths
    as given (a missing one is reported on its own line).

    Raises
    ------
    InvalidInputError
        For a folder with no image file.
    """
    out: list[Path] = []
    for item in map(Path, paths):
        if item.is_dir():
            found = in_name_order([p for p in item.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES])
            if not found:
                raise InvalidInputError(f"folder {item} holds no image files ({', '.join(sorted(IMAGE_SUFFIXES))})")
            out.extend(found)
        else:
            out.append(item)
    return out


def error_record(path: Path, message: str) -> Record:
    """The record of an image that could not be read or used (the message without the path
    the readers start it with: the record names the image)."""
    return {"image": str(path), "status": ERROR, "reason": message.removeprefix(f"{path}: ")}


def _safe(process: Callable[[Path], Record], path: Path) -> Record:
    """``process(path)``, or the error record of the problem it raised (the batch goes on)."""
    from ._main import one_line

    if not path.exists():
        return error_record(path, "no such file or folder")
    try:
        return process(path)
    except MemoryError as exc:
        from ._run_context import memory_message

        return error_record(path, memory_message(exc))
    except (StartrackError, ValueError, OSError) as exc:
        return error_record(path, one_line(exc))
    except Exception as exc:  # noqa: BLE001  # a fault on one image must not cost the rest of the batch
        interruption = hidden_interruption(exc)  # ... but Ctrl-C or SIGTERM inside compiled code stops it
        if interruption is not None:
            raise interruption from None
        return error_record(path, f"unexpected {type(exc).__name__} (a fault of startrack's, please report it): "
                                  f"{one_line(exc)}")


class _SafeProcess:
    """A picklable ``_safe(process, path)`` for the worker processes."""

    def __init__(self, process: Callable[[Path], Record]):
        self.process = process

    def __call__(self, path: Path) -> Record:
        return _safe(self.process, path)


def _records(spec: BatchSpec, images: list[Path], jobs: int, stack: ExitStack) -> Iterator[Record]:
    """The records in input order: here, or from ``jobs`` worker processes (forked where the
    platform can, so the loaded catalog, database and kernels are shared)."""
    task = _SafeProcess(spec.process)
    if jobs <= 1 or len(images) == 1:
        return map(task, images)
    import multiprocessing  # a single image's command does not pay for importing them
    from concurrent.futures import ProcessPoolExecutor

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    pool = stack.enter_context(ProcessPoolExecutor(max_workers=min(jobs, len(images)),
                                                   mp_context=multiprocessing.get_context(method)))
    return pool.map(task, images)


class _Bar:
    """startrack's progress bar on a terminal only, cleared before each output line."""

    def __init__(self, label: str, total: int):
        from ._progress import ProgressBar

        self.total, self.drawn = total, False
        self.bar = ProgressBar(label) if sys.stderr.isatty() else None

    def clear(self) -> None:
        """Erase a part-drawn bar, so that an output line on the same terminal starts clean."""
        if self.drawn:
            sys.stderr.write("\r\033[K")
            sys.stderr.flush()

    def __call__(self, done: int) -> None:
        if self.bar is not None:
            self.bar(done, self.total)
            self.drawn = done < self.total  # the bar ends its own line when complete


def _csv_writer(stack: ExitStack, spec: BatchSpec, csv_out: str | None, images: list[Path]):
    if csv_out is None:
        return None
    from ..io import open_output

    handle = stack.enter_context(open_output(csv_out, newline="", inputs=images))
    writer = csv.DictWriter(handle, fieldnames=list(spec.csv_columns), extrasaction="ignore")
    writer.writeheader()
    return writer


def _utf8_row(row: Record) -> Record:
    """``row`` with every text value encodable as UTF-8: a file name the file system holds as
    bytes that are not UTF-8 (decoded by Python as lone surrogates) is written with backslash
    escapes (``bad\\udcff.png``) instead of stopping the CSV."""
    return {key: value.encode("utf-8", "backslashreplace").decode("utf-8") if isinstance(value, str) else value
            for key, value in row.items()}


def _print_line(text: str) -> bool:
    """Print ``text`` to standard output; False (and later output goes to the null device) when
    its reader has gone (a broken pipe)."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return False
    return True


def run_batch(spec: BatchSpec, paths: Sequence[str], *, as_json: bool = False, csv_out: str | None = None,
              jobs: int = 1) -> int:
    """Run ``spec`` on every image of ``paths`` (files and folders) and write the outputs.

    Returns
    -------
    int
        The exit status: 0 when every image is done (``spec.done_statuses``), 1 when some are not
        (not solved, or an ``error``); misuse raises InvalidInputError before any image (exit 2).
    """
    from ..io import STDOUT

    images = expand_inputs(paths)
    width = min(max(len(str(p)) for p in images), 60)
    lines = csv_out != STDOUT  # with --csv -, the CSV is the only standard output
    records: list[Record] = []
    start = time.perf_counter()
    with ExitStack() as stack:
        writer = _csv_writer(stack, spec, csv_out, images)
        bar = _Bar(f"{spec.name}", len(images))
        if lines and not as_json:
            lines = _print_line(spec.header.format(image="image".ljust(width)))
        bar(0)
        for done, record in enumerate(_records(spec, images, jobs, stack), 1):
            bar.clear()
            if lines:
                lines = _print_line(json.dumps(record, allow_nan=False) if as_json else spec.line(record, width))
            if not lines and writer is None:  # nothing left to write: stop, as on SIGPIPE
                raise BrokenPipeError
            if writer is not None:
                writer.writerows(_utf8_row(row) for row in spec.csv_rows(record))
            records.append(record)
            bar(done)
    write_summary(spec, records, time.perf_counter() - start)
    return 0 if all(r["status"] in spec.done_statuses for r in records) else 1


def write_summary(spec: BatchSpec, records: list[Record], wall_s: float) -> None:
    """On stderr: ``startrack solve: 20 images in 3.1 s (0.16 s each): 18 solved, 2 not`` and,
    under it, each image that was not done with its status and reason."""
    failed = [r for r in records if r["status"] not in spec.done_statuses]
    n = len(records)
    word = "solved" if spec.name == "solve" else "done"
    lines = [f"startrack {spec.name}: {n} image{'s' * (n != 1)} in {wall_s:.2f} s ({wall_s / max(n, 1):.3f} s each): "
             f"{n - len(failed)} {word}, {len(failed)} not {word}"]
    for status in sorted({r["status"] for r in failed}):
        group = [r for r in failed if r["status"] == status]
        lines.append(f"  {status} ({len(group)}):")
        lines.extend(f"    {r['image']}: {r['reason'] or status}" for r in group)
    sys.stderr.write("\n".join(lines) + "\n")
    sys.stderr.flush()


def add_batch_options(parser) -> None:
    """--csv OUT and --jobs N (the image positional takes several files or folders)."""
    from ._common import positive_count

    parser.add_argument("--csv", metavar="OUT",
                        help="also write a CSV with one row per image (detect: per star) to OUT; - writes "
                             "it to standard output instead of the table")
    parser.add_argument("--jobs", type=positive_count, default=1, metavar="N",
                        help="images in N worker processes at once (default 1: all in this process)")


def batch_epilog() -> str:
    """The "batches" paragraph of the ``--help`` of the commands that take a batch (solve, detect).

    Returns
    -------
    str
        A heading and its lines (:func:`startrack.cli._common.wrap_help`), the batch's exit
        statuses last, ending with :data:`startrack.cli._common.FAULT_EXIT_STATUS`.
    """
    from ._common import FAULT_EXIT_STATUS, wrap_help  # not at import: a worker process does not need them

    return "batches (several images, a folder, or --csv)\n" + wrap_help(
        "One line per image (or one JSON object per line with --json), in the order given (a folder's image "
        "files by name), a progress bar on a terminal, and a summary on standard error naming each image not "
        "done and why. A file that cannot be read is reported on its line (status error), as is an unexpected "
        "error on one image, and the others go on. "
        "Exit status: 0 every image done; 1 some not (not solved, or an error); 2 misuse (a bad option, a "
        f"folder without images); {FAULT_EXIT_STATUS}").rstrip("\n")
