"""FITS images: read the first image HDU, write an image with optional binary tables.

Reading and writing go through ``astropy.io.fits``, which applies BZERO / BSCALE (a 16-bit FITS
with BZERO = 32768 comes back as uint16; a scaled one as float). Pixel (0, 0) of the array is
FITS pixel (1, 1) (see :mod:`startrack.conventions`).
"""

from __future__ import annotations

import gzip
import io
import os
import warnings
import zlib
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from astropy.io import fits
from astropy.table import Table
from numpy.typing import NDArray

from ..errors import ImageReadError, InvalidInputError
from ._atomic import write_output
from ._fits_cards import COMMENTARY, check_layout_cards, header_text, header_to_dict
from ._fits_plain import read_plain_fits
from ._limits import check_image_size

_STRUCTURAL = ("SIMPLE", "XTENSION", "BITPIX", "NAXIS", "EXTEND", "BZERO", "BSCALE", "PCOUNT",
               "GCOUNT", "END")
"""Keywords astropy derives from the data; dropped from a user header before writing."""


MAX_HEADER_BLOCKS = 2000
"""Largest primary header read (2,880-byte blocks: 5.8 MB, 72,000 cards); a longer one is refused."""

_BLOCK = 2880


def _primary_header(path: Path) -> tuple[bytes | None, bool]:
    """The primary header's blocks up to the one holding END (decompressed, for gzip), or None
    when the file ends before an END card (astropy then reports the truncation); and whether the
    file is gzip-compressed.

    Reads block by block, so a huge or endless header costs at most :data:`MAX_HEADER_BLOCKS`
    blocks, refused beyond that; astropy then parses only a header that is known to end.
    """
    with open(path, "rb") as raw:
        gzipped = raw.read(2) == b"\x1f\x8b"
    head = bytearray()
    try:
        with (gzip.open(path, "rb") if gzipped else open(path, "rb")) as fh:
            for _ in range(MAX_HEADER_BLOCKS):
                block = fh.read(_BLOCK)
                if len(block) < _BLOCK:
                    return None, gzipped
                head += block
                if any(block[i:i + 8] == b"END     " for i in range(0, _BLOCK, 80)):
                    return bytes(head), gzipped
    except (OSError, EOFError, zlib.error) as exc:
        raise ImageReadError(f"{path}: not a readable FITS file ({exc})") from exc
    raise ImageReadError(f"{path}: FITS header has no END card in its first {MAX_HEADER_BLOCKS} blocks "
                         f"({MAX_HEADER_BLOCKS * _BLOCK // 1000:,} kB); not an image startrack reads")


def _check_primary_header(path: Path) -> None:
    """Refuse a primary header that ends too late, or, in a gzip file, lays out its pixels
    wrongly (:func:`._fits_cards.check_layout_cards`) before astropy reads it. An uncompressed
    file's header is checked by the direct reader, which parses it anyway
    (:func:`._fits_plain.read_plain_fits`; parsing it here too cost 0.3 ms of a 1.4 ms read)."""
    head, gzipped = _primary_header(path)
    if head is None or not gzipped:
        return
    with warnings.catch_warnings():  # odd descriptive cards are left out of the header, not reported
        warnings.simplefilter("ignore")
        try:
            header = fits.Header.fromstring(header_text(head))
        except (ValueError, TypeError):
            return  # astropy's own read says what is wrong
    check_layout_cards(header, path)


def _usable_shape(hdu) -> tuple[int, ...] | None:
    """The data shape an image HDU's header declares, if it is 2-D or a (3, H, W) cube."""
    shape = tuple(int(n) for n in getattr(hdu, "shape", ()) or ())
    if len(shape) == 2 or (len(shape) == 3 and shape[0] == 3):
        return shape
    return None


def _image_hdu(hdus: fits.HDUList, path: Path, max_pixels: int | None) -> tuple[NDArray, fits.Header]:
    """Data and header of the first HDU holding a 2-D image or a (3, H, W) colour cube.

    The size is checked from the header before the data are read. The header is copied before
    the data are touched: astropy rewrites BITPIX and removes BZERO / BSCALE in memory once it
    scales the data, and we report the file's own cards.
    """
    shapes = []
    for hdu in hdus:
        if not getattr(hdu, "is_image", False):
            continue
        check_layout_cards(hdu.header, path)
        shape = _usable_shape(hdu)
        shapes.append(tuple(getattr(hdu, "shape", ())))
        if shape is None:
            continue
        check_image_size(shape[-1], shape[-2], max_pixels, path)
        header = hdu.header.copy()
        data = hdu.data
        if data is None:
            continue
        return (data, header) if data.ndim == 2 else (np.moveaxis(data, 0, -1), header)
    raise ImageReadError(
        f"{path}: FITS file has no 2-D image (or (3, H, W) colour cube); image HDU shapes: "
        f"{[s for s in shapes if s] or 'none'}"
    )


def read_fits(path: Path, max_pixels: int | None = None) -> tuple[NDArray, dict[str, Any], int]:
    """Read a FITS image.

    Parameters
    ----------
    path : Path
        A FITS file, plain or gzip-compressed.
    max_pixels : int, optional
        Largest width x height read (:mod:`startrack.io._limits`; None: the limit in force),
        checked from the header before the data are read.

    Returns
    -------
    data : ndarray, shape (H, W) or (H, W, 3)
        Native dtype in native byte order after BZERO / BSCALE, a copy independent of the file.
        A (3, H, W) colour cube is returned channels last.
    header : dict
        The cards of that HDU (see :func:`._fits_cards.header_to_dict`; unparsable ones left out).
    bit_depth : int
        ``abs(BITPIX)`` of that HDU.

    Raises
    ------
    ImageReadError
        If the file is truncated, corrupt, too large or holds no image.
    """
    _check_primary_header(path)
    plain = read_plain_fits(path, max_pixels, MAX_HEADER_BLOCKS)
    if plain is not None:
        return plain[0], header_to_dict(plain[1]), abs(int(plain[1]["BITPIX"]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            # our own handle, closed even when astropy fails while opening (it leaks its own then)
            with open(path, "rb") as fh, fits.open(fh, memmap=False, lazy_load_hdus=True) as hdus:
                data, header = _image_hdu(hdus, path, max_pixels)
                data = np.array(data, dtype=data.dtype.newbyteorder("="))
        except ImageReadError:
            raise
        except (OSError, ValueError, TypeError, IndexError, KeyError, EOFError, zlib.error, fits.VerifyError) as exc:
            # KeyError: a missing NAXISn in an extension's header; VerifyError: a card astropy needs unparsable
            raise ImageReadError(f"{path}: not a readable FITS file ({exc})") from exc
    if any("truncated" in str(w.message) for w in caught):
        raise ImageReadError(f"{path}: FITS file is truncated (shorter than its header says)")
    return data, header_to_dict(header), abs(int(header["BITPIX"]))


def _clean_header(header: Mapping[str, Any] | fits.Header | None) -> fits.Header:
    """A header without structural keywords; keys over 8 characters become HIERARCH cards."""
    out = fits.Header()
    if header is None:
        return out
    if not isinstance(header, Mapping | fits.Header):
        raise InvalidInputError(f"header must be a dict of cards or an astropy Header, got {type(header).__name__}")
    if isinstance(header, fits.Header):
        items = [(c.keyword, c.value if c.keyword in COMMENTARY else (c.value, c.comment))
                 for c in header.cards]
    else:
        items = list(header.items())
    for key, value in items:
        key = str(key).upper()
        if key.rstrip("0123456789") in _STRUCTURAL or not key:
            continue
        if key in COMMENTARY:
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
               tables: Mapping[str, Any] | None = None, *, inputs: Iterable[str | os.PathLike] = (),
               leading: Sequence[fits.ImageHDU] = ()) -> Path:
    """Write a 2-D image as a FITS primary HDU, with optional binary-table extensions.

    Parameters
    ----------
    path : str or Path
        The file to write, by the rules of :mod:`startrack.io._atomic` (never over an input;
        replaced only by a complete file; ``-``, devices and FIFOs written through).
    array : ndarray, shape (H, W)
        Integer or float pixel values, written as they are (uint16 is stored as BITPIX 16 with
        BZERO 32768, which astropy and every FITS reader turn back into uint16).
    header : dict or astropy.io.fits.Header, optional
        Extra cards: ``{key: value}`` or ``{key: (value, comment)}``; COMMENT / HISTORY may be
        lists. Structural keywords (BITPIX, NAXIS*, BZERO, ...) are dropped: they follow the data.
    tables : dict of name -> table, optional
        Each table (a dict of equal-length columns, a structured array or an astropy Table)
        becomes a binary-table extension with that EXTNAME, e.g. ``{"TRUTH": {...}}``.
    inputs : iterable of paths
        Files that must not be replaced.
    leading : sequence of ImageHDU
        Extensions written before the tables (see :mod:`startrack.io._truth_files`).

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    InvalidInputError
        If the array is not a 2-D numeric array or a table or header card is not valid.
    """
    return write_output(path, fits_bytes(array, header, tables, leading), inputs=inputs)


def fits_bytes(array: NDArray, header: Mapping | fits.Header | None = None, tables: Mapping[str, Any] | None = None,
               leading: Sequence[fits.ImageHDU] = ()) -> bytes:
    """The FITS file :func:`write_fits` writes, as bytes (same arguments and refusals)."""
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
    if tables is not None and not isinstance(tables, Mapping):
        raise InvalidInputError(f"tables must be a dict of name -> table, got {type(tables).__name__}")
    hdus = fits.HDUList([primary, *leading, *(_table_hdu(k, v) for k, v in (tables or {}).items())])
    buffer = io.BytesIO()
    try:
        hdus.writeto(buffer, output_verify="exception")
    except fits.VerifyError as exc:
        raise InvalidInputError(f"FITS header is not valid: {exc}") from exc
    return buffer.getvalue()
