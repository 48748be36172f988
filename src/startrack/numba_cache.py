"""Where numba keeps startrack's compiled loops, and clearing a damaged copy (docs/io.md, "Caches").

startrack's kernels (:mod:`startrack.identify._quad_kernel`, :mod:`startrack.identify._pose_kernel`)
are compiled by numba on first use and cached on disk (``cache=True``). Left to itself numba writes
that cache into ``__pycache__`` beside the installed package (read-only in a system install, shared
by every user) and trusts what it finds there: a damaged index or data file stops every later run
with an UnpicklingError. So:

* :func:`configure` points numba at ``<startrack cache>/numba`` (``$STARTRACK_CACHE_DIR/numba`` or
  the platform's user cache), unless the user set ``NUMBA_CACHE_DIR`` themselves. It runs when
  :mod:`startrack.cache` is imported, which every path to a kernel does before numba is imported;
  if numba was imported earlier, its ``config.CACHE_DIR`` is set instead.
* :func:`heal` checks the files of that folder once per process, before the first table is loaded
  from the cache: an index (``.nbi``) must be numba's version string followed by a complete pickle
  stream, a data file (``.nbc``) a complete pickle stream (its opcodes are walked to the STOP
  opcode without building anything, so nothing is imported); a file that fails is deleted, and
  numba compiles that function again (the slow start the cache is there to avoid) and rewrites it.
  Temporary files of killed writers (``*.tmp.*`` older than an hour) are removed too. A data file
  whose bytes are damaged inside the compiled code itself is beyond what can be checked without
  loading it.
* Files found whole are remembered in :data:`CHECKED_NAME` in that folder, by their size and
  modification time (ns): a later process reads only the files that are new or changed since
  (numba writes every file anew, through a temporary file and a rename, so a rewrite changes
  both), and otherwise only lists the folder, instead of reading in full a cache that grows with
  every edited kernel (``benchmarks/startup_benchmark.py`` times the first solve of a new process,
  this check included, and with ``--cold`` a fresh cache). A file damaged in place with its size
  and time kept as they were is not read again; remove :data:`CHECKED_NAME` to check everything.
"""

from __future__ import annotations

import io
import json
import os
import pickle
import pickletools
import sys
import time
from pathlib import Path

NUMBA_ENV_VAR = "NUMBA_CACHE_DIR"
STALE_TEMP_S = 3600.0
"""A numba temporary file untouched for this long belongs to a killed writer."""

CHECKED_NAME = ".startrack-checked.json"
"""The record of the files :func:`heal` found whole: ``{relative path: [size, mtime_ns]}``."""

_HEALED: set[Path] = set()


def numba_cache_dir(root: Path) -> Path:
    """startrack's numba folder inside the cache folder ``root``."""
    return root / "numba"


_CONFIGURED: list[Path] = []


def configured_dir() -> Path | None:
    """The folder :func:`configure` chose (None before, or when the user set NUMBA_CACHE_DIR)."""
    return _CONFIGURED[0] if _CONFIGURED else None


def configure(root: Path) -> Path | None:
    """Send numba's cache to ``numba_cache_dir(root)``; returns it, or None if the user chose one.

    Only the first call of a process decides (numba reads the setting when it compiles).
    """
    if _CONFIGURED:
        return _CONFIGURED[0]
    folder = numba_cache_dir(root)
    if os.environ.get(NUMBA_ENV_VAR) not in (None, "", str(folder)):  # the user's own choice
        return None
    _CONFIGURED.append(folder)
    if "numba" in sys.modules:
        from numba.core import config

        config.CACHE_DIR = str(folder)  # type: ignore[attr-defined]  # numba's config sets its names at run time
    os.environ[NUMBA_ENV_VAR] = str(folder)
    return folder


def _index_ok(data: bytes) -> bool:
    """An index is numba's version string (a pickle), then a pickled (stamp, overloads) pair."""
    stream = io.BytesIO(data)
    try:
        version = pickle.load(stream)
    except Exception:  # noqa: BLE001 - any failure to unpickle means a damaged index
        return False
    return isinstance(version, str) and _data_ok(stream.read())


def _data_ok(data: bytes) -> bool:
    """A complete pickle stream: its opcodes walked to STOP, no object built (nothing imported)."""
    try:
        opcodes = [op.name for op, _, _ in pickletools.genops(data)]
    except Exception:  # noqa: BLE001 - a truncated or garbled stream
        return False
    return bool(opcodes) and opcodes[-1] == "STOP"


def _check(path: Path) -> bool:
    """True if the cache file looks whole (see the module docstring)."""
    try:
        data = path.read_bytes()
    except OSError:
        return True  # unreadable now: numba will say so itself
    return _index_ok(data) if path.suffix == ".nbi" else _data_ok(data)


def heal(folder: Path | None) -> list[Path]:
    """Delete the damaged and stale files of startrack's numba cache (once per process per folder).

    A file recorded whole in :data:`CHECKED_NAME` with its present size and modification time is
    not read again. Returns the files removed; never raises.
    """
    if folder is None or folder in _HEALED or not folder.is_dir():
        return []
    _HEALED.add(folder)
    before = _read_checked(folder)
    checked: dict[str, list[int]] = {}
    removed, now = [], time.time()
    for path, size, mtime_ns in _cache_files(folder):
        name = path.relative_to(folder).as_posix()
        if ".tmp." in path.name:
            if now - mtime_ns * 1e-9 > STALE_TEMP_S and _unlink(path):
                removed.append(path)
        elif path.suffix in (".nbi", ".nbc"):
            stamp = [size, mtime_ns]
            if before.get(name) == stamp or _check(path):
                checked[name] = stamp
            elif _unlink(path):
                removed.append(path)
    if checked != before:
        _write_checked(folder, checked)
    return removed


def _cache_files(folder: Path):
    """(path, size, mtime_ns) of every file in ``folder`` and its subfolders; never raises."""
    pending = [folder]
    while pending:
        try:
            entries = list(os.scandir(pending.pop()))
        except OSError:
            continue
        for entry in entries:
            try:
                if entry.is_dir(follow_symlinks=False):
                    pending.append(Path(entry.path))
                elif entry.is_file(follow_symlinks=False):
                    info = entry.stat(follow_symlinks=False)
                    yield Path(entry.path), info.st_size, info.st_mtime_ns
            except OSError:
                continue


def _read_checked(folder: Path) -> dict[str, list[int]]:
    """The record of files found whole, or {} if it is absent or unreadable."""
    return read_record(folder / CHECKED_NAME)


def _write_checked(folder: Path, checked: dict[str, list[int]]) -> None:
    write_record(folder / CHECKED_NAME, checked)


def read_record(path: Path) -> dict[str, list[int]]:
    """A record of files found whole (a JSON object: name -> stamp), or {} if absent or unreadable.
    Also :mod:`startrack.cache`'s record of the table files it has checked."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return record if isinstance(record, dict) else {}


def write_record(path: Path, record: dict[str, list[int]], tmp: Path | None = None) -> None:
    """Replace a record atomically (through the temporary file ``tmp`` beside it, by default
    ``NAME.PID.tmp.NS``, and a rename); a failure is ignored (the files are then checked again by
    the next process)."""
    tmp = tmp or path.with_name(f"{path.name}.{os.getpid()}.tmp.{time.time_ns():x}")
    try:
        tmp.write_text(json.dumps(record, sort_keys=True))
        os.replace(tmp, path)
    except OSError:
        _unlink(tmp)


def _unlink(path: Path) -> bool:
    try:
        path.unlink()
    except OSError:
        return False
    return True
