"""Outputs that never destroy: a complete, checked write or the old file left as it was.

DESIGN.md §3 (Data) and docs/io.md ("Outputs"). Every writer of startrack goes through one of

* :func:`atomic_path` - yields a path for a writer that takes a file name (astropy, Pillow);
* :func:`open_output` - yields an open file, for text or bytes written as they come (a CSV row
  per frame);
* :func:`write_output` - writes bytes or text in one call;
* :func:`atomic_group` - several files that belong together (an image and its sidecar): all of
  them are replaced, or none.

How a path is written is decided by :func:`startrack.io._targets.output_target`: a regular file
(or a new one) is written to a temporary file ``.NAME.PID.RANDOM.tmp`` in the same folder,
flushed to disk (``fsync``) and renamed over the target only after the write has completed with
no error, keeping the old file's permission bits; on any error, an interrupt or a SIGTERM turned
into an exception (``startrack`` does that), the temporary file is removed and the target keeps
its previous content. A kill that leaves a temporary file behind is cleaned up by the next write
to the same name (the file names the dead process). Standard output (``-``), devices and FIFOs
are written through in place. Errors name the target, never the temporary file.
"""

from __future__ import annotations

import hashlib
import io
import os
import re
import shutil
import sys
import tempfile
import uuid
from collections.abc import Iterable, Iterator, Sequence
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import IO

from ..errors import OutputError
from ._targets import OutputTarget, output_target

_COPY_CHUNK = 1 << 20


# --- temporary files ---------------------------------------------------------------------------
_LONGEST_STEM = 200
"""Longest part of a target's name kept in its temporary file's name (file names stop at 255 bytes)."""


def _temp_stem(name: str) -> str:
    if len(name.encode()) <= _LONGEST_STEM:
        return name
    return name[:100] + "~" + hashlib.sha256(name.encode()).hexdigest()[:16]


def temp_name(target: Path) -> Path:
    """The temporary file beside ``target``: ``.NAME.PID.RANDOM.tmp`` (a long NAME shortened)."""
    return target.with_name(f".{_temp_stem(target.name)}.{os.getpid()}.{uuid.uuid4().hex[:12]}.tmp")


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


def remove_stale_temps(folder: Path, name: str | None = None) -> int:
    """Remove the temporary files in ``folder`` (of ``name`` only, if given) whose writer has died.

    A temporary file names its writer's process id (:func:`temp_name`); it is stale when no process
    has that id. Returns the number of files removed; never raises.
    """
    prefix = re.escape(f".{_temp_stem(name)}.") if name else r"\..+\."
    pattern = re.compile(prefix + r"(\d+)\.[0-9a-f]+\.tmp$")
    removed = 0
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return 0
    for entry in entries:
        match = pattern.match(entry.name)
        if match and int(match.group(1)) != os.getpid() and not _pid_alive(int(match.group(1))):
            try:
                os.unlink(entry.path)
                removed += 1
            except OSError:
                pass
    return removed


def discard(path: Path) -> None:
    """Remove a temporary file if it is there; never raises."""
    try:
        path.unlink(missing_ok=True)
    except OSError:
        pass


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _write_error(target: OutputTarget, exc: OSError) -> OutputError:
    reason = exc.strerror or str(exc) or type(exc).__name__
    return OutputError(f"cannot write {target.given}: {reason}; nothing was changed there")


def _keep_mode(tmp: Path, target: Path) -> None:
    try:
        os.chmod(tmp, target.stat().st_mode & 0o7777)
    except OSError:
        pass


def _commit(tmp: Path, target: OutputTarget) -> None:
    """Rename a finished (fsynced) temporary file over a regular target, keeping its permissions."""
    _keep_mode(tmp, target.file)
    os.replace(tmp, target.file)


# --- writing through ---------------------------------------------------------------------------
def _stdout_write(data: bytes) -> None:
    sys.stdout.flush()
    buffer = getattr(sys.stdout, "buffer", None)
    if buffer is not None:
        buffer.write(data)
        buffer.flush()
        return
    try:
        sys.stdout.write(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise OutputError("cannot write binary data to standard output here (it takes text only); "
                          "give a file name") from None


def _open_through(target: OutputTarget) -> IO[bytes]:
    """The existing device, FIFO or /dev path, opened for writing without creating or truncating it."""
    fd = os.open(target.file, os.O_WRONLY | os.O_APPEND)
    return os.fdopen(fd, "wb")


def _copy_through(source: Path, target: OutputTarget) -> None:
    with open(source, "rb") as src:
        if target.is_stdout:
            while chunk := src.read(_COPY_CHUNK):
                _stdout_write(chunk)
            return
        with _open_through(target) as dst:
            shutil.copyfileobj(src, dst, _COPY_CHUNK)


# --- the public writers ------------------------------------------------------------------------
def _scratch(target: OutputTarget, stack: ExitStack) -> Path:
    """Where the writer writes: beside a regular target, else in a private temporary folder."""
    if target.through:
        folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="startrack-out-")))
        return folder / (Path(target.given).name or "stdout")
    remove_stale_temps(target.file.parent, target.file.name)
    return temp_name(target.file)


@contextmanager
def atomic_path(path: str | os.PathLike, *, inputs: Iterable[str | os.PathLike] = ()) -> Iterator[Path]:
    """Yield a path to write; on success the content replaces (or is written through to) ``path``.

    Parameters
    ----------
    path : str or Path
        The output (see :mod:`startrack.io._targets` for what is replaced, written through or refused).
    inputs : iterable of paths
        Files that must not be replaced.

    Raises
    ------
    InvalidInputError
        For a path that is refused (a folder, a missing folder, an input, ...), before anything is written.
    OutputError
        If writing fails (a full disk, no permission); the target is then unchanged.
    """
    with atomic_group([path], inputs=inputs) as (tmp,):
        yield tmp


@contextmanager
def atomic_group(paths: Sequence[str | os.PathLike], *,
                 inputs: Iterable[str | os.PathLike] = ()) -> Iterator[list[Path]]:
    """Yield one path to write per output; on success all outputs are replaced together.

    Every target is checked before the body runs; the renames happen only once every file has
    been written. If a rename fails part way, the files already replaced get their old content
    back (kept through a hard link while the group commits). Written-through targets (devices,
    standard output) are written last, after the regular files.
    """
    inputs = list(inputs)
    targets = [output_target(p, inputs) for p in paths]
    with ExitStack() as stack:
        tmps = [_scratch(t, stack) for t in targets]
        try:
            yield tmps
            _commit_group(targets, tmps)
        except OutputError:
            raise
        except OSError as exc:
            failed = next((t for t, tmp in zip(targets, tmps, strict=True) if exc.filename in (
                str(tmp), str(t.path or ""))), targets[0])
            raise _write_error(failed, exc) from exc
        finally:
            for tmp, target in zip(tmps, targets, strict=True):
                if not target.through:
                    discard(tmp)


def _backup(target: OutputTarget) -> Path | None:
    """A hard link to the current content of a regular target (None if it has none or links fail)."""
    if not target.file.is_file():
        return None
    backup = temp_name(target.file)
    try:
        os.link(target.file, backup)
    except OSError:
        return None
    return backup


def _undo(target: OutputTarget, backup: Path | None, existed: bool) -> None:
    """Put back what a regular target held before the group replaced it."""
    if backup is not None:
        os.replace(backup, target.file)
    elif not existed:
        target.file.unlink(missing_ok=True)


def _replace_all(regular: list[tuple[OutputTarget, Path]]) -> None:
    """Rename every temporary file over its target; on a failure undo the renames already done."""
    existed = [t.file.exists() for t, _ in regular]
    backups = [_backup(t) for t, _ in regular] if len(regular) > 1 else [None] * len(regular)
    done = 0
    try:
        for target, tmp in regular:
            _commit(tmp, target)
            done += 1
    except BaseException:
        for k in range(done):
            _undo(regular[k][0], backups[k], existed[k])
        raise
    finally:
        for backup in backups:
            if backup is not None:
                discard(backup)


def _commit_group(targets: list[OutputTarget], tmps: list[Path]) -> None:
    regular = [(t, tmp) for t, tmp in zip(targets, tmps, strict=True) if not t.through]
    for target, tmp in regular:
        if not tmp.is_file():
            raise OutputError(f"cannot write {target.given}: the writer produced no file")
        _fsync(tmp)
    _replace_all(regular)
    for target, tmp in zip(targets, tmps, strict=True):
        if target.through:
            _copy_through(tmp, target)


@contextmanager
def open_output(path: str | os.PathLike, mode: str = "w", *, inputs: Iterable[str | os.PathLike] = (),
                newline: str | None = None) -> Iterator[IO]:
    """An open file whose content replaces ``path`` when the block ends without an error.

    Parameters
    ----------
    path : str or Path
        The output; ``-`` is standard output, devices and FIFOs are written as the data come.
    mode : {"w", "wb"}
        Text (UTF-8) or bytes.
    inputs : iterable of paths
        Files that must not be replaced.
    newline : str, optional
        As for :func:`open` (``""`` for the csv module).

    Raises
    ------
    InvalidInputError, OutputError
        As for :func:`atomic_path`.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"mode must be 'w' or 'wb', got {mode!r}")
    target = output_target(path, inputs)
    if target.is_stdout:
        yield _stdout_stream(mode, newline)
        sys.stdout.flush()
        return
    if target.through:
        raw = _open_through(target)
        with raw if mode == "wb" else io.TextIOWrapper(raw, encoding="utf-8", newline=newline) as fh:
            yield fh
        return
    with atomic_path(path, inputs=inputs) as tmp, open(tmp, mode, newline=newline,
                                                        encoding=None if mode == "wb" else "utf-8") as fh:
        yield fh


def _stdout_stream(mode: str, newline: str | None) -> IO:
    if mode == "w":
        return sys.stdout
    buffer = getattr(sys.stdout, "buffer", None)
    if buffer is None:
        raise OutputError("cannot write binary data to standard output here (it takes text only); give a file name")
    return buffer


def write_output(path: str | os.PathLike, data: bytes | str, *,
                 inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``data`` (bytes, or text as UTF-8) to ``path`` by the rules of :func:`atomic_path`."""
    blob = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    with atomic_path(path, inputs=inputs) as tmp:
        tmp.write_bytes(blob)
    return Path(path)
