"""The direct read of a plain FITS image: a 2-D 8- or 16-bit integer primary array.

A star camera's raw frame is usually that: an uncompressed primary HDU of BITPIX 16 with BZERO
32768 (unsigned 16-bit pixels) or 0, or BITPIX 8. For those, the pixels are read with one
``np.fromfile`` and converted (to native byte order; the sign bit flipped for BZERO 32768,
which is the same as adding 32768), instead of through astropy's scaled-data machinery
(``benchmarks/image_path_benchmark.py`` prints the read time of a FITS frame). Anything else
(gzip, BSCALE, BLANK, floats, extensions, cubes) returns None and :func:`.fitsfile.read_fits`
reads it with astropy, as before. The header is astropy's own
parse of the same cards, so both paths report the same header.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
from astropy.io import fits
from numpy.typing import NDArray

from ._fits_cards import check_layout_cards, header_text
from ._limits import check_image_size

BLOCK = 2880
"""A FITS block (bytes)."""

_DTYPES: dict[int, np.dtype] = {8: np.dtype(np.uint8), 16: np.dtype(">u2")}


def _header_bytes(path: Path, max_blocks: int) -> bytes | None:
    """The primary header's blocks up to the one holding END, or None if there is none in reach
    (or the file is gzip-compressed)."""
    with open(path, "rb") as fh:
        head = b""
        for _ in range(max_blocks):
            block = fh.read(BLOCK)
            if len(block) < BLOCK or (not head and block[:2] == b"\x1f\x8b"):
                return None
            head += block
            if any(block[i:i + 8] == b"END     " for i in range(0, BLOCK, 80)):
                return head
    return None


def _plain_layout(header: fits.Header) -> tuple[int, int, int, bool] | None:
    """(width, height, BITPIX, unsigned) of a header this module reads, else None."""
    bitpix, bzero = header.get("BITPIX"), header.get("BZERO", 0)
    sizes = [header.get("NAXIS1"), header.get("NAXIS2")]
    plain = (header.get("SIMPLE") is True and header.get("NAXIS") == 2 and bitpix in _DTYPES
             and all(isinstance(n, int) and not isinstance(n, bool) and n > 0 for n in sizes)
             and header.get("BSCALE", 1) == 1 and "BLANK" not in header
             and (bzero == 0 or (bitpix == 16 and bzero == 32768)))
    if not plain:
        return None
    return int(header["NAXIS1"]), int(header["NAXIS2"]), int(bitpix), bzero == 32768


def read_plain_fits(path: Path, max_pixels: int | None, max_blocks: int) -> tuple[NDArray, fits.Header] | None:
    """Pixels and header of a plain FITS image (module docstring), or None to read it otherwise.

    Parameters
    ----------
    path : Path
        The file (its header already checked to end within ``max_blocks`` blocks). Its cards that
        lay out the pixels are checked here (:func:`._fits_cards.check_layout_cards`).
    max_pixels : int or None
        As in :func:`startrack.io._limits.check_image_size` (checked before the pixels are read).
    max_blocks : int
        Most header blocks searched for END.

    Returns
    -------
    (data, header) or None
        ``data`` (H, W) in native byte order: uint8 (BITPIX 8), uint16 (BITPIX 16, BZERO 32768)
        or int16 (BITPIX 16, BZERO 0), as astropy returns them. None for a gzip file, a header
        this module does not read, or a file shorter than its header says (astropy then says why).
    """
    head = _header_bytes(path, max_blocks)
    if head is None:
        return None
    with warnings.catch_warnings():  # odd cards: astropy's own read (the other path) says what is wrong
        warnings.simplefilter("ignore")
        try:
            header = fits.Header.fromstring(header_text(head))
        except (ValueError, TypeError):
            return None
    check_layout_cards(header, path)  # before the cards below are trusted
    layout = _plain_layout(header)
    if layout is None:
        return None
    width, height, bitpix, unsigned = layout
    check_image_size(width, height, max_pixels, path)
    dtype = _DTYPES[bitpix]
    if os.path.getsize(path) < len(head) + width * height * dtype.itemsize:
        return None
    data = np.fromfile(path, dtype=dtype, count=width * height, offset=len(head)).reshape(height, width)
    if bitpix == 16:
        data = data.astype(np.uint16)  # native byte order, a copy owned by us
        if unsigned:
            data ^= np.uint16(0x8000)  # = stored int16 + 32768
        else:
            data = data.view(np.int16)
    return data, header
