"""What an output path names, and the inputs an output must never replace (docs/io.md, "Outputs").

:func:`output_target` sorts a path into one of two kinds before anything is written:

* **replaced** - a regular file, a path that does not exist yet, or a symbolic link to either: the
  new content goes to a temporary file beside the file itself (beside the link's target for a
  link, which is kept) and is renamed over it once complete (:mod:`startrack.io._atomic`);
* **written through** - ``-`` (standard output), a character device (``/dev/null``, a terminal), a
  FIFO, a link to one, and anything under ``/dev`` or ``/proc`` (``/dev/stdout``, ``/dev/fd/3``):
  the bytes are written into it in order and nothing is created, renamed or deleted there.

Refused with :class:`~startrack.errors.InvalidInputError`: a folder, a missing folder, a block
device (a disk), a socket, a path under ``/dev`` or ``/proc`` that does not exist, and any file
that is one of the command's inputs (the same file by device and inode, also through a link).

The inputs are those named in ``inputs=`` and, inside :func:`protect_inputs` (every ``startrack``
command runs inside it), every file the readers of :mod:`startrack.io` have read.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path

from ..errors import InvalidInputError

STDOUT = "-"
"""The output path that means standard output."""

_PASS_THROUGH_ROOTS = ("/dev/", "/proc/")
_READ_INPUTS: ContextVar[set[tuple[int, int]] | None] = ContextVar("startrack_read_inputs", default=None)


@dataclass(frozen=True)
class OutputTarget:
    """A checked output path.

    Attributes
    ----------
    given : str
        The path as the caller gave it (used in messages).
    path : Path or None
        The file to replace (a link resolved to its target); None for standard output.
    through : bool
        True to write into the existing target in place (standard output, a device, a FIFO).
    """

    given: str
    path: Path | None
    through: bool

    @property
    def is_stdout(self) -> bool:
        return self.path is None

    @property
    def file(self) -> Path:
        """The file of a target that is not standard output (ValueError for standard output)."""
        if self.path is None:
            raise ValueError("standard output has no file path")
        return self.path


def _identity(path: str | os.PathLike) -> tuple[int, int] | None:
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return (st.st_dev, st.st_ino) if stat.S_ISREG(st.st_mode) else None


@contextmanager
def protect_inputs() -> Iterator[None]:
    """Within this block, every file read by :mod:`startrack.io` is an input no output may replace."""
    token = _READ_INPUTS.set(set())
    try:
        yield
    finally:
        _READ_INPUTS.reset(token)


def note_input(path: str | os.PathLike) -> None:
    """Record ``path`` as an input of the running command (no-op outside :func:`protect_inputs`)."""
    inputs = _READ_INPUTS.get()
    if inputs is None:
        return
    identity = _identity(path)
    if identity is not None:
        inputs.add(identity)


def _check_not_input(given: str, path: str | os.PathLike, inputs: Iterable[str | os.PathLike]) -> None:
    identity = _identity(path)
    if identity is None:
        return
    read = _READ_INPUTS.get() or set()
    if identity in read or any(_identity(p) == identity for p in inputs):
        raise InvalidInputError(f"cannot write {given}: it is one of the inputs of this command; "
                                "give another output file name")


def _under_pass_through_root(text: str) -> bool:
    return any(text.startswith(root) for root in _PASS_THROUGH_ROOTS)


def _through_kind(given: str, mode: int | None) -> bool:
    """True for a target written through; raises for one that is refused."""
    if mode is None:
        raise InvalidInputError(f"cannot write {given}: it does not exist, and nothing is created under "
                                "/dev or /proc")
    if stat.S_ISBLK(mode):
        raise InvalidInputError(f"cannot write {given}: it is a block device (a disk), not a file")
    if stat.S_ISSOCK(mode) or stat.S_ISDIR(mode):
        what = "a socket" if stat.S_ISSOCK(mode) else "a folder"
        raise InvalidInputError(f"cannot write {given}: it is {what}, give a file name")
    return True


def _mode(path: str) -> int | None:
    try:
        return os.stat(path).st_mode
    except OSError:
        return None


def output_target(path: str | os.PathLike, inputs: Iterable[str | os.PathLike] = ()) -> OutputTarget:
    """Check an output path and say how it is written (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The output; ``"-"`` is standard output.
    inputs : iterable of paths
        Files this output must not replace (besides those recorded by :func:`note_input`).

    Raises
    ------
    InvalidInputError
        For a folder, a missing folder, a block device, a socket, a missing path under /dev or
        /proc, or an input.
    """
    if not isinstance(path, str | os.PathLike):
        raise InvalidInputError(f"output path must be a file name (str or os.PathLike) or '-' for standard output, "
                                f"got {type(path).__name__}")
    given = os.fspath(path)
    if isinstance(given, bytes):
        given = os.fsdecode(given)
    if given == STDOUT:
        return OutputTarget(given, None, True)
    if not given:
        raise InvalidInputError("output path must not be empty (give a file name, or - for standard output)")
    absolute, real = os.path.abspath(given), os.path.realpath(given)
    mode = _mode(given)
    _check_not_input(given, given, inputs)
    if _under_pass_through_root(absolute) or _under_pass_through_root(real) or (
            mode is not None and not stat.S_ISREG(mode) and not stat.S_ISDIR(mode)):
        return OutputTarget(given, Path(given), _through_kind(given, mode))
    target = Path(real)
    if mode is not None and stat.S_ISDIR(mode):
        raise InvalidInputError(f"cannot write {given}: it is a folder, give a file name")
    if not target.parent.is_dir():
        raise InvalidInputError(f"cannot write {given}: folder {Path(given).parent} does not exist")
    return OutputTarget(given, target, False)
