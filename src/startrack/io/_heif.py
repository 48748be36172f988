"""HEIC / HEIF photos, the default format of recent phones, through ``pillow-heif`` (libheif).

A HEIF file is an ISO base media file: a ``ftyp`` box whose brand names it (:data:`HEIF_BRANDS`:
HEVC-coded still images and sequences). Its size is read from the file's boxes before any pixel is
decoded (:mod:`startrack.io._limits`); 10- and 12-bit images keep their native counts (libheif
hands them over in 16-bit samples shifted to the top bits, shifted back here), 8-bit images stay
uint8; the EXIF block is read as a JPEG's is (``DateTimeOriginal`` gives the epoch). The colour
rule of :mod:`startrack.io._channels` then applies.

``pillow_heif`` is imported only when a HEIF file is read (``pip install 'startrack[heif]'``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ImageReadError
from ._limits import check_image_size
from ._raster import exif_header

HEIF_BRANDS = frozenset({b"heic", b"heix", b"hevc", b"hevx", b"heim", b"heis", b"mif1", b"msf1"})
"""``ftyp`` major brands of HEVC-coded HEIF files (ISO/IEC 23008-12)."""


def is_heif(head: bytes) -> bool:
    """Whether a file's first 12 bytes are a HEIF ``ftyp`` box."""
    return len(head) >= 12 and head[4:8] == b"ftyp" and head[8:12] in HEIF_BRANDS


def read_heif(path: Path, max_pixels: int | None = None) -> tuple[NDArray, dict[str, Any], int]:
    """Decode the primary image of a HEIF file.

    Returns
    -------
    data : ndarray, shape (H, W, 3 or 4)
        uint8, or uint16 with the file's own bit depth of counts (10 or 12 bits).
    header : dict
        The EXIF fields (:func:`startrack.io._raster.exif_header`).
    bit_depth : int

    Raises
    ------
    ImageReadError
        pillow-heif is not installed, the file is truncated or corrupt, or over ``max_pixels``.
    """
    try:
        import pillow_heif
    except ImportError:
        raise ImageReadError(f"{path}: a HEIC / HEIF file; reading it needs pillow-heif "
                             "(pip install 'startrack[heif]')") from None
    try:
        heif = pillow_heif.open_heif(path, convert_hdr_to_8bit=False)  # the boxes only, not the pixels
    except (ValueError, RuntimeError, OSError, EOFError) as exc:
        raise ImageReadError(f"{path}: HEIF file is truncated or corrupt ({exc})") from None
    width, height = heif.size
    check_image_size(width, height, max_pixels, path)
    try:
        data = np.asarray(heif)
    except (ValueError, RuntimeError, OSError, EOFError) as exc:
        raise ImageReadError(f"{path}: HEIF image data cannot be decoded ({exc})") from None
    bits = int(heif.info.get("bit_depth") or 8)
    if data.dtype == np.uint16 and bits < 16:
        data = data >> np.uint16(16 - bits)
    return data, exif_header(heif.info.get("exif")), bits
