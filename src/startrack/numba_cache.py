"""Where numba keeps startrack's compiled loops, and clearing a damaged copy (docs/io.md, "Caches").

startrack's kernels (:mod:`startrack.identify._quad_kernel`, :mod:`startrack.identify._pose_kernel`)
are compiled by numba on first use and cached on disk (``cache=True``). Left to itself numba writes
that cache into ``__pycache__`` beside the installed package (read-only in a system install, shared
by every user) and trusts what it finds there: a damaged index or data file stops every later run
with an UnpicklingError. So:

* :func:`configure` points numba at ``<startrack cache>/numba`` (``$STARTRACK_CACHE_DIR/numba`` or
  the platform's user cache), unless the user set ``NUMBA_CACHE_DIR`` themselves. It runs when
  :mod:`startrack.cache` is imported, which every path to a kernel does before numba is imported;
  if numba was imported earlier, its ``config.CACHE_DIR`` is set too. It only sets names (no file
  is touched), so importing :mod:`startrack.cache` stays cheap.
* :func:`configured_dir`, called where the cache is first needed (before the first table is
  loaded, and before the detector's kernels are imported), checks once per process that numba's
  folder (startrack's, or the user's ``NUMBA_CACHE_DIR``) can be created and written, by writing
  and removing a file (``os.access`` says yes to root on a read-only mount). If it cannot, numba
  would cache into the package's own ``__pycache__`` (as root) or stop with "cannot cache
  function ...: no locator available"; instead numba is sent to a private temporary folder of
  this process (``startrack-numba-*``, removed at exit), and one
  :class:`~startrack.errors.CacheWarning` names the folder and says that compiled code is not kept
  for later runs and how to choose another folder (:func:`keeps_compiled_code` is then False).
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
import warnings
from pathlib import Path

NUMBA_ENV_VAR = "NUMBA_CACHE_DIR"
STALE_TEMP_S = 3600.0
"""A numba temporary file untouched for this long belongs to a killed writer."""

PRIVATE_PREFIX = "startrack-numba-"
"""The name prefix of the temporary folder numba caches into when its own folder cannot be written."""
WRITE_TEST_PREFIX = ".startrack-write-test-"

CHECKED_NAME = ".startrack-checked.json"
"""The record of the files :func:`heal` found whole: ``{relative path: [size, mtime_ns]}``."""

_HEALED: set[Path] = set()


def numba_cache_dir(root: Path) -> Path:
    """startrack's numba folder inside the cache folder ``root``."""
    return root / "numba"


_CONFIGURED: list[Path] = []
_CHOSEN: list[Path | None] = []
"""What the first :func:`configured_dir` of the process decided (the folder to heal, or None)."""
_UNWRITABLE: list[Path] = []
"""numba's folder, when :func:`configured_dir` found that it cannot be written."""


def configured_dir() -> Path | None:
    """The folder of startrack's numba cache, checked once per process; None before
    :func:`configure`, or when the user's own (writable) ``NUMBA_CACHE_DIR`` is used.

    The first call checks that numba's folder can be created and written (:func:`_write_error`);
    if not, numba is sent to a private temporary folder, which is returned, and one
    :class:`~startrack.errors.CacheWarning` says so. Call it before numba compiles (or loads) a
    kernel: numba chooses a function's cache folder when the function is defined.
    """
    if not _CHOSEN and (_CONFIGURED or os.environ.get(NUMBA_ENV_VAR)):
        _CHOSEN.append(_checked_choice())
    return _CHOSEN[0] if _CHOSEN else None


def keeps_compiled_code() -> bool:
    """False when this process's compiled code goes to a temporary folder removed at exit
    (numba's folder could not be written), so that nothing is cached for later runs."""
    return not _UNWRITABLE


def configure(root: Path) -> Path | None:
    """Send numba's cache to ``numba_cache_dir(root)``; returns it, or None if the user chose one.

    Only the first call of a process decides (numba reads the setting when it compiles). No file
    is touched: :func:`configured_dir` checks the folder where the cache is first needed.
    """
    if _CONFIGURED:
        return _CONFIGURED[0]
    folder = numba_cache_dir(root)
    if os.environ.get(NUMBA_ENV_VAR) not in (None, "", str(folder)):  # the user's own choice
        return None
    _CONFIGURED.append(folder)
    _point_numba_at(folder)
    return folder


def _point_numba_at(folder: Path) -> None:
    """Set numba's cache folder: the environment (read when numba is imported, and again by its
    compiler) and, if numba is imported already, its config."""
    if "numba" in sys.modules:
        from numba.core import config

        config.CACHE_DIR = str(folder)  # type: ignore[attr-defined]  # numba's config sets its names at run time
    os.environ[NUMBA_ENV_VAR] = str(folder)


def _checked_choice() -> Path | None:
    """The folder to heal after checking numba's folder; a private temporary one if it cannot be
    written (with one warning), None for the user's own writable folder."""
    wanted = Path(os.environ.get(NUMBA_ENV_VAR) or _CONFIGURED[0])
    ours = _CONFIGURED[0] if _CONFIGURED and wanted == _CONFIGURED[0] else None
    error = _write_error(wanted)
    if error is None:
        return ours
    _UNWRITABLE.append(wanted)
    private = _private_folder()
    if private is not None:
        _point_numba_at(private)
    _warn_unwritable(wanted, error, private, users=ours is None)
    return private


def _write_error(folder: Path) -> str | None:
    """Why ``folder`` cannot be created or written (a file is written there and removed), or None
    if it can."""
    test = folder / f"{WRITE_TEST_PREFIX}{os.getpid()}-{time.time_ns():x}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with open(test, "xb") as fh:
            fh.write(b"0")
    except OSError as exc:
        return exc.strerror or str(exc)
    finally:
        _unlink(test)
    return None


def _private_folder() -> Path | None:
    """A new temporary folder of this process, removed when it exits (None if none can be made)."""
    import atexit
    import tempfile

    try:
        folder = Path(tempfile.mkdtemp(prefix=PRIVATE_PREFIX))
    except OSError:
        return None
    atexit.register(_remove_private, folder, os.getpid())
    return folder


def _remove_private(folder: Path, owner: int) -> None:
    """Remove the private folder at exit, in the process that made it only (a forked child that
    runs the exit handlers leaves it to its parent)."""
    if os.getpid() == owner:
        import shutil

        shutil.rmtree(folder, ignore_errors=True)


def _warn_unwritable(folder: Path, error: str, private: Path | None, users: bool) -> None:
    """The one warning of a numba folder that cannot be written (``users``: set by the user)."""
    from .errors import CacheWarning

    fix = f"set {NUMBA_ENV_VAR}" if users else f"set STARTRACK_CACHE_DIR or {NUMBA_ENV_VAR}"
    where = (f"goes to a temporary folder ({private})" if private is not None
             else "has nowhere to go (no temporary folder could be made either)")
    warnings.warn(CacheWarning(
        f"cannot write the numba cache folder {folder}: {error}; compiled code {where} and is not kept for "
        f"later runs (every run compiles again, about a minute); {fix} to a writable folder"), stacklevel=4)


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


def prepare() -> None:
    """Point numba at startrack's cache folder (importing :mod:`startrack.cache` does) and check
    the folder and its files (:func:`configured_dir`, :func:`heal`), once a process. Call it before
    importing a module of compiled kernels: numba picks a function's cache folder when the
    function is defined, and one not pointed here writes beside the package's source."""
    from . import cache  # noqa: F401  # configures numba's folder on import

    heal(configured_dir())


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
