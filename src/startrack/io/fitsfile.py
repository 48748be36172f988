"""FITS images: read the first image HDU, write an image with optional binary tables.

Reading and writing go through ``astropy.io.fits``, which applies BZERO / BSCALE (a 16-bit FITS
with BZERO = 32768 comes back as uint16; a scaled one as float). Pixel (0, 0) of the array is
FITS pixel (1, 1) (see :mod:`startrack.conventions`).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from astropy.io import fits
from astropy.table import Table
from numpy.typing import NDArray

from ..errors import ImageReadError, InvalidInputError
from .atomic import atomic_path

_COMMENTARY = ("COMMENT", "HISTORY")
_STRUCTURAL = ("SIMPLE", "XTENSION", "BITPIX", "NAXIS", "EXTEND", "BZERO", "BSCALE", "PCOUNT",
               "GCOUNT", "END")
"""Keywords astropy derives from the data; dropped from a user header before writing."""


def header_to_dict(header: fits.Header) -> dict[str, Any]:
    """FITS header cards as a dict: keyword -> value; COMMENT and HISTORY as lists of strings."""
    out: dict[str, Any] = {}
    for card in header.cards:
        key = card.keyword
        if not key:
            continue
        if key in _COMMENTARY:
            out.setdefault(key, []).append(str(card.value))
        elif isinstance(card.value, bool | int | float | str):
            out[key] = card.value
        else:  # astropy's Undefined (a keyword with no value)
            out[key] = None
    return out


def _image_hdu(hdus: fits.HDUList, path: Path) -> tuple[NDArray, fits.Header]:
    """Data and header of the first HDU holding a 2-D image or a (3, H, W) colour cube.

    The header is copied before the data are touched: astropy rewrites BITPIX and removes
    BZERO / BSCALE in memory once it scales the data, and we report the file's own cards.
    """
    shapes = []
    for hdu in hdus:
        if not getattr(hdu, "is_image", False):
            continue
        header = hdu.header.copy()
        data = hdu.data
        if data is None:
            continue
        shapes.append(data.shape)
        if data.ndim == 2:
            return data, header
        if data.ndim == 3 and data.shape[0] == 3:
            return np.moveaxis(data, 0, -1), header
    raise ImageReadError(
        f"{path}: FITS file has no 2-D image (or (3, H, W) colour cube); image HDU shapes: "
        f"{shapes or 'none'}"
    )


def read_fits(path: Path) -> tuple[NDArray, dict[str, Any], int]:
    """Read a FITS image.

    Returns
    -------
    data : ndarray, shape (H, W) or (H, W, 3)
        Native dtype in native byte order after BZERO / BSCALE, a copy independent of the file.
        A (3, H, W) colour cube is returned channels last.
    header : dict
        The cards of that HDU (see :func:`header_to_dict`).
    bit_depth : int
        ``abs(BITPIX)`` of that HDU.

    Raises
    ------
    ImageReadError
        If the file is truncated, corrupt or holds no image.
    """
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with fits.open(path, memmap=False) as hdus:
                data, header = _image_hdu(hdus, path)
                data = np.array(data, dtype=data.dtype.newbyteorder("="))
        except ImageReadError:
            raise
        except (OSError, ValueError, TypeError, IndexError) as exc:
            raise ImageReadError(f"{path}: not a readable FITS file ({exc})") from exc
    if any("truncated" in str(w.message) for w in caught):
        raise ImageReadError(f"{path}: FITS file is truncated (shorter than its header says)")
    return data, header_to_dict(header), abs(int(header["BITPIX"]))


def _clean_header(header: Mapping[str, Any] | fits.Header | None) -> fits.Header:
    """A header without structural keywords; keys over 8 characters become HIERARCH cards."""
    out = fits.Header()
    if header is None:
        return out
    if isinstance(header, fits.Header):
        items = [(c.keyword, c.value if c.keyword in _COMMENTARY else (c.value, c.comment))
                 for c in header.cards]
    else:
        items = list(header.items())
    for key, value in items:
        key = str(key).upper()
        if key.rstrip("0123456789") in _STRUCTURAL or not key:
            continue
        if key in _COMMENTARY:
            for text in value if isinstance(value, list | tuple) else [value]:
                out.append((key, str(text)))
            continue
        out["HIERARCH " + key if len(key) > 8 else key] = value
    return out


def _table_hdu(name: str, table: Any) -> fits.BinTableHDU:
    try:
        hdu = fits.table_to_hdu(Table(table))
    except (ValueError, TypeError) as exc:
        raise InvalidInputError(
            f"table {name!r} must be a dict of equal-length 1-D arrays, a structured array or an "
            f"astropy Table ({exc})"
        ) from exc
    hdu.name = name.upper()
    return hdu


def write_fits(path: str | os.PathLike, array: NDArray, header: Mapping | fits.Header | None = None,
               tables: Mapping[str, Any] | None = None) -> Path:
    """Write a 2-D image as a FITS primary HDU, with optional binary-table extensions.

    Parameters
    ----------
    path : str or Path
        The file to write; replaced atomically (temporary file in the same folder, then rename).
    array : ndarray, shape (H, W)
        Integer or float pixel values, written as they are (uint16 is stored as BITPIX 16 with
        BZERO 32768, which astropy and every FITS reader turn back into uint16).
    header : dict or astropy.io.fits.Header, optional
        Extra cards: ``{key: value}`` or ``{key: (value, comment)}``; COMMENT / HISTORY may be
        lists. Structural keywords (BITPIX, NAXIS*, BZERO, ...) are dropped: they follow the data.
    tables : dict of name -> table, optional
        Each table (a dict of equal-length columns, a structured array or an astropy Table)
        becomes a binary-table extension with that EXTNAME, e.g. ``{"TRUTH": {...}}``.

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    InvalidInputError
        If the array is not a 2-D numeric array or a table or header card is not valid.
    """
    array = np.asarray(array)
    if array.ndim != 2 or array.dtype.kind not in "uif" or array.size == 0:
        raise InvalidInputError(
            f"FITS image must be a non-empty 2-D integer or float array, got shape {array.shape} "
            f"and dtype {array.dtype}"
        )
    try:
        primary = fits.PrimaryHDU(data=array, header=_clean_header(header))
    except (ValueError, TypeError, KeyError) as exc:
        raise InvalidInputError(f"FITS header is not valid: {exc}") from exc
    hdus = fits.HDUList([primary, *(_table_hdu(k, v) for k, v in (tables or {}).items())])
    with atomic_path(path) as tmp:
        try:
            hdus.writeto(tmp, output_verify="exception")
        except fits.VerifyError as exc:
            raise InvalidInputError(f"FITS header is not valid: {exc}") from exc
    return Path(path)
