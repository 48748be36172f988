"""The user cache of derived tables (DESIGN.md §3, Data).

Tables are stored as uncompressed ``.npz`` files named by a hash of their inputs, with a JSON
header that repeats the key and a format version. A file that is corrupt, truncated or from
another version is rebuilt, never trusted. Writes are atomic: a temporary file in the same folder,
then a rename.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from .errors import CacheError

ENV_VAR = "STARTRACK_CACHE_DIR"
_META = "__meta__"


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


def load(kind: str, version: int, params: Mapping) -> dict[str, np.ndarray] | None:
    """The cached arrays for these inputs, or None if absent, corrupt or stale."""
    key = input_key(kind, version, params)
    path = _path(kind, key)
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as npz:
            meta = json.loads(str(npz[_META]))
            if meta.get("key") != key or meta.get("version") != version:
                return None
            return {name: npz[name] for name in npz.files if name != _META}
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError, json.JSONDecodeError):
        return None


def save(kind: str, version: int, params: Mapping, arrays: Mapping[str, np.ndarray]) -> Path:
    """Write the arrays atomically and return the file's path."""
    key = input_key(kind, version, params)
    path = _path(kind, key)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        meta = json.dumps({"key": key, "version": version, "kind": kind})
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **{_META: np.array(meta)}, **arrays)
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    except OSError as exc:
        raise CacheError(f"cannot write the cache file {path}: {exc}; set {ENV_VAR} to a writable folder") from exc
    return path


def load_or_build(kind: str, version: int, params: Mapping,
                  build: Callable[[], Mapping[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Cached arrays for these inputs, building and saving them first if needed."""
    arrays = load(kind, version, params)
    if arrays is None:
        arrays = dict(build())
        save(kind, version, params, arrays)
    return arrays
