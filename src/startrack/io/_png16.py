"""16-bit colour PNGs (RGB, RGBA, grey + alpha), which Pillow decodes only to their high bytes.

Stacking and raw-development programs (Siril, GIMP, RawTherapee, darktable) export 16-bit RGB
PNGs; read through Pillow they would keep 8 of their 16 bits, the faint stars' counts among the
lost ones. This reader inflates the IDAT stream (never more than the rows the header declares),
undoes each row's filter (PNG specification, section 9: none, Sub, Up, Average, Paeth; a compiled
loop, :mod:`._png_kernels`) and reads the samples as big-endian 16-bit integers. Interlaced
(Adam7) files are refused with a message; so is a stream that ends early or a row filter other than
the five.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path
from typing import BinaryIO

import numpy as np
from numpy.typing import NDArray

from ..errors import ImageReadError
from ._pixel_data import _PNG_CHANNELS, png_chunks, png_data_size

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
COLOUR_TYPES = (2, 4, 6)
"""The PNG colour types read here at 16 bits: RGB, grey + alpha, RGBA."""


def is_png16_colour(head: bytes) -> bool:
    """Whether a file starting with ``head`` (at least 26 bytes) is a 16-bit RGB, RGBA or grey +
    alpha PNG (its IHDR, which must come first)."""
    return head[:8] == PNG_SIGNATURE and len(head) > 25 and head[12:16] == b"IHDR" and head[24] == 16 \
        and head[25] in COLOUR_TYPES


def read_png16_colour(path: Path, fh: BinaryIO) -> NDArray[np.uint16]:
    """The samples of the 16-bit colour PNG open as ``fh``: uint16, (H, W, 3) RGB, (H, W, 4) RGBA,
    or (H, W) the grey of grey + alpha (its alpha dropped, as Pillow's 8-bit ``LA`` is read).

    Raises
    ------
    ImageReadError
        For an interlaced file, image data that end early or do not inflate, or a row filter
        type other than 0-4.
    """
    width, height, colour, interlaced, data = _idat_stream(path, fh)
    if interlaced:
        raise ImageReadError(f"{path}: interlaced (Adam7) 16-bit colour PNG is not supported; save it without "
                             "interlacing, or as 16-bit TIFF or FITS")
    channels = _PNG_CHANNELS[colour]
    stride = width * channels * 2
    rows = _unfiltered(data, height, stride, channels * 2, path)
    samples = rows.view(">u2").reshape(height, width, channels)
    return (samples[..., 0] if channels == 2 else samples).astype(np.uint16)  # grey + alpha: the grey


def _idat_stream(path: Path, fh: BinaryIO) -> tuple[int, int, int, bool, NDArray[np.uint8]]:
    """Width, height, colour type, interlacing and the inflated image data (uint8, exactly the
    bytes its rows need)."""
    header, expected = None, 0
    inflater, parts, size = zlib.decompressobj(), [], 0
    try:
        for kind, length in png_chunks(fh):
            if kind == b"IHDR" and length >= 13:
                header = struct.unpack(">IIBBBBB", fh.read(13))
                expected = png_data_size(header[0], header[1], header[2], header[3], header[6] == 1)
            elif kind == b"IDAT" and expected and size < expected:
                part = inflater.decompress(fh.read(length), expected - size)
                parts.append(part)
                size += len(part)
    except zlib.error as exc:
        raise ImageReadError(f"{path}: PNG file is truncated or corrupt (its image data cannot be inflated: {exc})"
                             ) from exc
    if header is None:
        raise ImageReadError(f"{path}: PNG file has no IHDR chunk")
    if size < expected:
        raise ImageReadError(f"{path}: PNG file is truncated or corrupt (its image data stop after {size:,} of the "
                             f"{expected:,} bytes its rows need)")
    return header[0], header[1], header[3], header[6] == 1, np.frombuffer(b"".join(parts), np.uint8)


def _unfiltered(data: NDArray[np.uint8], height: int, stride: int, bpp: int, path: Path) -> NDArray[np.uint8]:
    """The rows' bytes, (height, stride), with their filters undone (:func:`._png_kernels.unfilter`)."""
    from ..numba_cache import prepare

    prepare()
    from ._png_kernels import unfilter

    out = np.empty((height, stride), np.uint8)
    bad = unfilter(data, height, stride, bpp, out)
    if bad >= 0:
        raise ImageReadError(f"{path}: PNG file is corrupt (row {bad} has filter type {data[bad * (stride + 1)]}; "
                             "PNG defines 0-4)")
    return out


def warm_up_png16() -> None:
    """Compile (once after an install, about 4 s) or load the row-filter loop, so that the first
    16-bit colour PNG a command reads does not wait for it (``startrack warm-up`` calls this)."""
    stream = np.zeros(2 * 7, np.uint8)
    stream[0], stream[7] = 1, 4  # two rows of one 16-bit RGB pixel: Sub, then Paeth
    stream.setflags(write=False)  # as the inflated stream is (np.frombuffer): numba types it apart
    _unfiltered(stream, 2, 6, 6, Path("warm-up"))
