"""The user cache of derived tables (DESIGN.md §3, Data; docs/io.md, "Caches").

Tables are stored as uncompressed ``.npz`` files named by a hash of their inputs. Each file holds
a JSON header (``__meta__``) with the key, the format and table versions, and a manifest of its
arrays: name, dtype, shape and the CRC-32 of the array's bytes. A file that fails a check is
rebuilt, never trusted: its arrays missing, extra, of another shape or type, or replaced.

Loading maps the file (copy-on-write) rather than reading it: :func:`save` pads the zip members
so that every array starts at a multiple of 64 bytes, and a load takes views of the mapping: it
neither reads the whole file nor checks its CRCs, so its time does not grow with the size of the
table (the default pattern database is the largest), and a solve then touches only the pages it
uses (``benchmarks/startup_benchmark.py`` times the database load of a new process). The CRCs
are computed the first time a process meets a file, which is then remembered in
:data:`VERIFIED_NAME` by its size, times and inode; later loads compare only names, dtypes and
shapes with the manifest. A file rewritten or replaced changes its stamp and is checked again;
one damaged in place with all of its stamp kept is not (as for numba's cache,
:mod:`startrack.numba_cache`); remove the record to check every file again. Files of the
earlier, unaligned layout are read (zipfile checks their members' CRCs), checked and written
again aligned, once.

Writes are atomic (a temporary file ``.NAME.PID.RANDOM.tmp`` in the same folder, flushed to disk,
then renamed); temporary files of writers that died are removed by the next write. A folder that
cannot be written means working without the cache: the table is built, used for this process,
and one :class:`~startrack.errors.CacheWarning` says so. The numba cache of the compiled loops
lives in the ``numba`` folder of the same cache (:mod:`startrack.numba_cache`).
"""

from __future__ import annotations

import hashlib
import json
import math
import mmap
import os
import struct
import time
import warnings
import zipfile
import zlib
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
from numpy.lib import format as npy_format

from . import numba_cache
from .errors import CacheError, CacheWarning
from .io import discard, remove_stale_temps, temp_name

ENV_VAR = "STARTRACK_CACHE_DIR"
FORMAT = 2
"""Version of the file layout (2: with the array manifest)."""

_META = "__meta__"
_ALIGN = 64
"""Arrays start at multiples of this many bytes in a file written by :func:`save`."""

VERIFIED_NAME = ".startrack-verified.json"
"""The record, in the cache folder, of the table files found whole: ``{file name: [size,
mtime_ns, ctime_ns, inode]}``."""
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


def manifest(arrays: Mapping[str, np.ndarray], crc: bool = True) -> dict[str, list]:
    """``{name: [dtype, shape, crc32]}`` of the arrays (the CRC of their C-order bytes; 0 when
    ``crc`` is False)."""
    out = {}
    for name in sorted(arrays):
        array = np.asarray(arrays[name])
        check = zlib.crc32(np.ascontiguousarray(array).view(np.uint8).ravel().data if array.size else b"") if crc else 0
        out[name] = [array.dtype.str, list(array.shape), check]
    return out


def _write_npz(fh, arrays: Mapping[str, np.ndarray]) -> None:
    """An uncompressed ``.npz`` (numpy reads it as ever) whose arrays start at multiples of 64
    bytes in the file, so that :func:`_read` maps them: each zip member's local header is padded
    with an extra field (id 0xD935, as Android's zipalign pads) and ``.npy`` headers are 64-byte
    multiples themselves."""
    with zipfile.ZipFile(fh, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name, value in arrays.items():
            array = np.asanyarray(value)
            member = f"{name}.npy"
            info = zipfile.ZipInfo(member, date_time=time.localtime()[:6])
            info.compress_type = zipfile.ZIP_STORED
            info.file_size = array.nbytes + 4096  # an upper bound: zipfile's choice of zip64 headers
            pad = -(fh.tell() + 30 + len(member.encode()) + 4) % _ALIGN
            info.extra = struct.pack("<HH", 0xD935, pad) + bytes(pad)
            with zf.open(info, "w") as out:
                npy_format.write_array(out, array, allow_pickle=False)


def _read(path: Path) -> tuple[dict, dict[str, np.ndarray], bool]:
    """The header and the arrays of a cache file, and whether every array was mapped.

    The file is mapped into memory copy-on-write (reads come from the page cache, a write to an
    array stays in this process); an array whose bytes are not stored plainly at an offset its
    dtype allows (a file written before the aligned layout, by ``np.savez``) is read instead.
    """
    with open(path, "rb") as fh, zipfile.ZipFile(fh) as zf:
        infos = {info.filename.removesuffix(".npy"): info for info in zf.infolist()}
        with zf.open(infos.pop(_META)) as member:
            meta = json.loads(str(npy_format.read_array(member, allow_pickle=False)))
        whole = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_COPY)
        arrays, mapped = {}, True
        for name, info in infos.items():
            array = _mapped(fh, info, whole)
            if array is None:
                with zf.open(info) as member:  # zipfile checks this member's CRC
                    array = npy_format.read_array(member, allow_pickle=False)
                mapped = False
            arrays[name] = array
    return meta, arrays, mapped


def _mapped(fh, info: zipfile.ZipInfo, whole: mmap.mmap) -> np.ndarray | None:
    """The array of one zip member as a view of the mapped file, or None when it cannot be one
    (compressed, an object dtype, an offset its dtype does not allow, sizes that disagree)."""
    fh.seek(info.header_offset)
    local = fh.read(30)
    if info.compress_type != zipfile.ZIP_STORED or len(local) != 30 or local[:4] != b"PK\x03\x04":
        return None
    name_len, extra_len = struct.unpack("<HH", local[26:30])
    start = info.header_offset + 30 + name_len + extra_len
    fh.seek(start)
    version = npy_format.read_magic(fh)
    if version not in ((1, 0), (2, 0)):
        return None
    read_header = npy_format.read_array_header_1_0 if version == (1, 0) else npy_format.read_array_header_2_0
    shape, fortran, dtype = read_header(fh)
    offset, count = fh.tell(), math.prod(shape)
    if dtype.hasobject or offset % dtype.alignment or offset - start + count * dtype.itemsize != info.file_size:
        return None
    return np.frombuffer(whole, dtype=dtype, count=count, offset=offset).reshape(shape, order="F" if fortran else "C")


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
    """The cached arrays for these inputs, or None if absent, damaged, incomplete or stale.

    The arrays are views of the mapped file (:func:`_read`). Their CRCs are computed the first
    time a process meets the file; a file already found whole (:data:`VERIFIED_NAME`, by its
    size, times and inode) has only its names, dtypes and shapes compared with the manifest. A
    file of the unaligned layout that passes is written again aligned, once.
    """
    numba_cache.heal(numba_cache.configured_dir())
    key = input_key(kind, version, params)
    path = _path(kind, key)
    try:
        stamp = _stamp(path)
        meta, arrays, mapped = _read(path)
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError, json.JSONDecodeError, zlib.error):
        return None
    if (meta.get("key"), meta.get("version"), meta.get("format")) != (key, version, FORMAT):
        return None
    record = numba_cache.read_record(path.parent / VERIFIED_NAME)
    if record.get(path.name) == stamp:
        return arrays if _layout(meta.get("arrays")) == _layout(manifest(arrays, crc=False)) else None
    if meta.get("arrays") != manifest(arrays):
        return None
    if not mapped:
        _realign(kind, version, params, arrays)
    else:
        _record_verified(path, stamp)
    return arrays


def _stamp(path: Path) -> list[int]:
    """What changes when a file is written or replaced: size, modification and change times (ns),
    inode."""
    info = path.stat()
    return [info.st_size, info.st_mtime_ns, info.st_ctime_ns, info.st_ino]


def _layout(entries) -> dict | None:
    """``{name: [dtype, shape]}`` of a manifest (its CRCs left out)."""
    return {name: entry[:2] for name, entry in entries.items()} if isinstance(entries, dict) else None


def _record_verified(path: Path, stamp: list[int]) -> None:
    """Add the file to the record of files found whole (entries of files now gone are dropped)."""
    target = path.parent / VERIFIED_NAME
    record = {name: old for name, old in numba_cache.read_record(target).items() if (path.parent / name).exists()}
    record[path.name] = stamp
    numba_cache.write_record(target, record, temp_name(target))


def _realign(kind: str, version: int, params: Mapping, arrays: Mapping[str, np.ndarray]) -> None:
    """Write a verified file of the unaligned layout again in the aligned one (best effort)."""
    try:
        save(kind, version, params, arrays)
    except CacheError:
        pass


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
            _write_npz(fh, {_META: np.array(meta), **arrays})
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
