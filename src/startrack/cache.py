"""The user cache of derived tables (DESIGN.md §3, Data; docs/io.md, "Caches").

Tables are stored as uncompressed ``.npz`` files named by a hash of their inputs. Each file holds
a JSON header (``__meta__``) with the key, the format and table versions, and a manifest of its
arrays: name, dtype, shape and the CRC-32 of the array's bytes. On load, the zip format's own
CRCs catch damaged bytes, and the manifest catches a file whose arrays are missing, extra, of
another shape or type, or replaced: a file that fails any check is rebuilt, never trusted.

Writes are atomic (a temporary file ``.NAME.PID.RANDOM.tmp`` in the same folder, flushed to disk,
then renamed); temporary files of writers that died are removed by the next write. A folder that
cannot be written means working without the cache: the table is built, used for this process,
and one :class:`~startrack.errors.CacheWarning` says so. The numba cache of the compiled loops
lives in the ``numba`` folder of the same cache (:mod:`startrack.numba_cache`).
"""

from __future__ import annotations

import hashlib
import json
import os
import time
import warnings
import zipfile
import zlib
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from . import numba_cache
from .errors import CacheError, CacheWarning
from .io.atomic import discard, remove_stale_temps, temp_name

ENV_VAR = "STARTRACK_CACHE_DIR"
FORMAT = 2
"""Version of the file layout (2: with the array manifest)."""

_META = "__meta__"
_WARNED: set[Path] = set()


def cache_dir() -> Path:
    """The cache folder: ``$STARTRACK_CACHE_DIR``, else the platform's user cache + ``startrack``."""
    env = os.environ.get(ENV_VAR)
    if env:
        return Path(env).expanduser()
    if os.name == "nt":
        base = Path(os.environ.get("LOCALAPPDATA", Path.home() / "AppData" / "Local"))
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    return base / "startrack"


def input_key(kind: str, version: int, params: Mapping) -> str:
    """A short stable hash of what a table is built from."""
    blob = json.dumps({"kind": kind, "version": version, "params": params}, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def _path(kind: str, key: str) -> Path:
    return cache_dir() / f"{kind}-{key}.npz"


def manifest(arrays: Mapping[str, np.ndarray]) -> dict[str, list]:
    """``{name: [dtype, shape, crc32]}`` of the arrays (the CRC of their C-order bytes)."""
    out = {}
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        out[name] = [array.dtype.str, list(array.shape), zlib.crc32(array.view(np.uint8).ravel()
                                                                    if array.size else b"")]
    return out


def _read(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    with np.load(path, allow_pickle=False) as npz:
        meta = json.loads(str(npz[_META]))
        return meta, {name: npz[name] for name in npz.files if name != _META}


def is_current(kind: str, version: int, params: Mapping) -> bool:
    """True if a cache file for these inputs exists in the current layout (only its header is read;
    :func:`load` still checks the arrays). Lets a caller announce a rebuild before it starts."""
    key = input_key(kind, version, params)
    try:
        with np.load(_path(kind, key), allow_pickle=False) as npz:
            meta = json.loads(str(npz[_META]))
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError, json.JSONDecodeError, zlib.error):
        return False
    return (meta.get("key"), meta.get("version"), meta.get("format")) == (key, version, FORMAT)


def load(kind: str, version: int, params: Mapping) -> dict[str, np.ndarray] | None:
    """The cached arrays for these inputs, or None if absent, damaged, incomplete or stale."""
    numba_cache.heal(numba_cache.configured_dir())
    key = input_key(kind, version, params)
    path = _path(kind, key)
    if not path.exists():
        return None
    try:
        meta, arrays = _read(path)
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError, json.JSONDecodeError, zlib.error):
        return None
    expected = (key, version, FORMAT)
    if (meta.get("key"), meta.get("version"), meta.get("format")) != expected:
        return None
    if meta.get("arrays") != manifest(arrays):
        return None
    return arrays


def save(kind: str, version: int, params: Mapping, arrays: Mapping[str, np.ndarray]) -> Path:
    """Write the arrays atomically and return the file's path.

    Raises
    ------
    CacheError
        If the folder cannot be created or written (the message names the final file, never the
        temporary one, and says how to choose another folder).
    """
    key = input_key(kind, version, params)
    path = _path(kind, key)
    meta = json.dumps({"key": key, "version": version, "format": FORMAT, "kind": kind, "arrays": manifest(arrays)})
    tmp = temp_name(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temps(path.parent)
        _remove_old_temps(path.parent)
        with open(tmp, "wb") as fh:
            np.savez(fh, **{_META: np.array(meta)}, **arrays)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        raise CacheError(f"cannot write the cache file {path}: {exc.strerror or exc}; set {ENV_VAR} "
                         "to a writable folder") from None
    finally:
        discard(tmp)
    return path


def _remove_old_temps(folder: Path) -> None:
    """Remove temporary files of the previous layout (``NAME-KEYxxxx.tmp``) untouched for an hour."""
    cutoff = time.time() - numba_cache.STALE_TEMP_S
    for path in folder.glob("*.tmp"):
        try:
            if not path.name.startswith(".") and path.stat().st_mtime < cutoff:
                path.unlink()
        except OSError:
            pass


def _warn_once(exc: CacheError) -> None:
    folder = cache_dir()
    if folder not in _WARNED:
        _WARNED.add(folder)
        warnings.warn(CacheWarning(f"{exc}; going on without the cache (tables are rebuilt in every run)"),
                      stacklevel=3)


def load_or_build(kind: str, version: int, params: Mapping,
                  build: Callable[[], Mapping[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Cached arrays for these inputs, building and saving them first if needed.

    If the cache cannot be written, the built arrays are returned all the same, with one
    :class:`~startrack.errors.CacheWarning` per process and folder.
    """
    arrays = load(kind, version, params)
    if arrays is None:
        arrays = dict(build())
        try:
            save(kind, version, params, arrays)
        except CacheError as exc:
            _warn_once(exc)
    return arrays


numba_cache.configure(cache_dir())
