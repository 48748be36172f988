"""A minimal baseline TIFF writer, and a reader for the 16-bit colour TIFFs Pillow truncates.

Pillow reads 16-bit-per-sample RGB(A) TIFFs as 8-bit RGB(A), silently keeping only the high
byte, and cannot write them. startrack keeps native bit depths, so:

* :func:`tiff_bytes` encodes every TIFF startrack writes (uncompressed, one strip,
  little-endian; uint8 / uint16 / float32 grey, uint8 / uint16 RGB), and
* :func:`read_tiff16_colour` decodes 16-bit RGB(A) TIFFs stored in strips, contiguously
  (PlanarConfiguration 1), uncompressed or Deflate-compressed, with or without the horizontal
  differencing predictor. Other 16-bit colour layouts raise
  :class:`~startrack.errors.ImageReadError`.

Tag numbers and field types are those of the TIFF 6.0 specification.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from ..errors import ImageReadError, InvalidInputError

_SHORT, _LONG = 3, 4
_FORMATS = {_SHORT: "H", _LONG: "I"}
_DEFLATE = (8, 32946)
_SAMPLE_FORMATS = {("u", 1): 1, ("u", 2): 1, ("f", 4): 3}
"""(dtype kind, item size) the writer accepts, with their SampleFormat (1 = unsigned, 3 = float)."""


# --- writing ---------------------------------------------------------------------------------
def _check_writable(array: NDArray) -> None:
    colour = array.ndim == 3 and array.shape[-1] == 3
    if not (array.ndim == 2 or colour):
        raise InvalidInputError(
            f"TIFF image must have shape (H, W) or (H, W, 3), got {array.shape}"
        )
    if _sample_format(array) is None or (colour and array.dtype.kind == "f"):
        raise InvalidInputError(
            f"TIFF image dtype must be uint8, uint16 or (grey only) float32, got {array.dtype}; "
            "convert explicitly, e.g. np.clip(a, 0, 65535).round().astype(np.uint16)"
        )
    if array.size == 0:
        raise InvalidInputError(f"TIFF image must not be empty, got shape {array.shape}")


def _sample_format(array: NDArray) -> int | None:
    return _SAMPLE_FORMATS.get((array.dtype.kind, array.dtype.itemsize))


def _entry(tag: int, kind: int, values: tuple[int, ...], extra_offset: int) -> tuple[bytes, bytes]:
    """One 12-byte IFD entry and the out-of-line bytes it points to (empty when inline)."""
    payload = struct.pack("<" + _FORMATS[kind] * len(values), *values)
    if len(payload) <= 4:
        return struct.pack("<HHI", tag, kind, len(values)) + payload.ljust(4, b"\0"), b""
    return struct.pack("<HHII", tag, kind, len(values), extra_offset), payload


def tiff_bytes(array: NDArray) -> bytes:
    """Encode an image as an uncompressed little-endian baseline TIFF (one strip).

    Parameters
    ----------
    array : ndarray, shape (H, W) or (H, W, 3)
        uint8 or uint16 (grey or RGB), or float32 (grey). Values are written as they are.

    Raises
    ------
    InvalidInputError
        For another shape or dtype, or an image too large for a classic (32-bit) TIFF.
    """
    array = np.asarray(array)
    _check_writable(array)
    height, width = array.shape[:2]
    spp = 1 if array.ndim == 2 else 3
    data = np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("<")).tobytes()
    if len(data) > 2**32 - 4096:
        raise InvalidInputError(f"image of {len(data)} bytes is too large for a classic TIFF")
    bits = (array.dtype.itemsize * 8,) * spp
    fields = [
        (256, _LONG, (width,)), (257, _LONG, (height,)), (258, _SHORT, bits), (259, _SHORT, (1,)),
        (262, _SHORT, (1 if spp == 1 else 2,)), (273, _LONG, (8,)), (277, _SHORT, (spp,)),
        (278, _LONG, (height,)), (279, _LONG, (len(data),)), (284, _SHORT, (1,)),
        (339, _SHORT, (_sample_format(array),) * spp),
    ]
    ifd_offset = 8 + len(data) + (len(data) % 2)
    extra_offset = ifd_offset + 2 + 12 * len(fields) + 4
    entries, extra = b"", b""
    for tag, kind, values in fields:
        entry, payload = _entry(tag, kind, values, extra_offset + len(extra))
        entries += entry
        extra += payload
    header = b"II" + struct.pack("<HI", 42, ifd_offset)
    ifd = struct.pack("<H", len(fields)) + entries + struct.pack("<I", 0)
    return header + data + b"\0" * (len(data) % 2) + ifd + extra


# --- reading 16-bit colour -------------------------------------------------------------------
def is_tiff16_colour(tags: Mapping[int, Any]) -> bool:
    """True if Pillow's TIFF tags describe 16-bit samples with more than one sample per pixel."""
    bits = tags.get(258, (8,))
    bits = bits if isinstance(bits, tuple) else (bits,)
    samples = tags.get(277, 1)  # not a number: not this layout (Pillow's own read then says what is wrong)
    return isinstance(samples, int) and samples > 1 and bool(bits) and max(bits) == 16


_TAG_NAMES = {256: "ImageWidth", 257: "ImageLength", 259: "Compression", 273: "StripOffsets", 277: "SamplesPerPixel",
              279: "StripByteCounts", 284: "PlanarConfiguration", 317: "Predictor"}
"""The tags the 16-bit colour reader reads (TIFF 6.0 names)."""


def _tag_values(tags: Mapping[int, Any], tag: int, path: Path) -> tuple[int, ...]:
    """The integer values of a required tag; an ImageReadError naming the tag when it is missing,
    empty or not made of integers."""
    value = tags.get(tag)
    values = tuple(value) if isinstance(value, tuple | list) else (value,)
    if value is None or not values or not all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        what = "has no" if value is None else f"has an invalid {_TAG_NAMES[tag]} ({value!r}) instead of a valid"
        raise ImageReadError(f"{path}: corrupt or unsupported TIFF: its directory {what} {_TAG_NAMES[tag]} "
                             f"(tag {tag}), which a 16-bit colour TIFF in strips needs")
    return values


def _tag_int(tags: Mapping[int, Any], tag: int, path: Path, default: int | None = None) -> int:
    """The single value (>= 1) of a tag, ``default`` when it is absent and has one; else as
    :func:`_tag_values`."""
    if tag not in tags and default is not None:
        return default
    values = _tag_values(tags, tag, path)
    if len(values) != 1 or values[0] < 1:
        raise ImageReadError(f"{path}: corrupt or unsupported TIFF: {_TAG_NAMES[tag]} (tag {tag}) is {values}; "
                             "it must be one integer >= 1")
    return values[0]


def _read_at(fh: BinaryIO, offset: int, count: int, size: int, path: Path) -> bytes:
    if offset + count > size:
        raise ImageReadError(f"{path}: TIFF file is truncated (a strip ends past the file end)")
    fh.seek(offset)
    return fh.read(count)


def _inflate(chunk: bytes, limit: int, path: Path) -> bytes:
    """Deflate-decompress a strip, refusing one that inflates past ``limit`` bytes (what the rest
    of the image can hold) before more than one byte past it is produced."""
    try:
        data = zlib.decompressobj().decompress(chunk, limit + 1)
    except zlib.error as exc:
        raise ImageReadError(f"{path}: TIFF strip is truncated or corrupt ({exc})") from exc
    if len(data) > limit:
        raise ImageReadError(f"{path}: a TIFF strip inflates past the image's size as its header gives it; "
                             "the file is corrupt or not what it claims")
    return data


def _strip_bytes(fh: BinaryIO, tags: Mapping[int, Any], expected: int, path: Path) -> bytes:
    """The concatenated, decompressed strips of a TIFF file's first image, at most ``expected`` bytes."""
    compression = _tag_int(tags, 259, path, default=1)
    if compression != 1 and compression not in _DEFLATE:
        raise ImageReadError(
            f"{path}: 16-bit colour TIFF with compression {compression} is not supported "
            "(only uncompressed or Deflate keep all 16 bits here); save it uncompressed, as "
            "16-bit greyscale, or as FITS"
        )
    offsets, counts = _tag_values(tags, 273, path), _tag_values(tags, 279, path)
    if len(offsets) != len(counts):
        raise ImageReadError(f"{path}: corrupt or unsupported TIFF: {len(offsets)} StripOffsets (tag 273) but "
                             f"{len(counts)} StripByteCounts (tag 279); there must be one of each per strip")
    size = fh.seek(0, 2)
    chunks, total = [], 0
    for offset, count in zip(offsets, counts, strict=True):
        if total >= expected:
            break
        chunk = _read_at(fh, offset, count, size, path)
        chunk = _inflate(chunk, expected - total, path) if compression in _DEFLATE else chunk[:expected - total]
        chunks.append(chunk)
        total += len(chunk)
    return b"".join(chunks)


def read_tiff16_colour(path: Path, fh: BinaryIO, tags: Mapping[int, Any]) -> NDArray[np.uint16]:
    """Decode a 16-bit RGB(A) TIFF that Pillow would truncate to 8 bits.

    Parameters
    ----------
    path : Path
        The file, for error messages.
    fh : binary file
        The file, open (only its strips are read).
    tags : mapping
        Pillow's ``tag_v2`` of the first image (its size already checked against the limit).

    Returns
    -------
    ndarray, shape (H, W, C), uint16 in native byte order

    Raises
    ------
    ImageReadError
        For tiled or planar-separate layouts, compressions other than Deflate, a truncated file,
        or a directory without the tags it needs (size, samples, strip offsets and byte counts).
    """
    if 322 in tags or _tag_int(tags, 284, path, default=1) != 1:
        raise ImageReadError(
            f"{path}: 16-bit colour TIFF stored in tiles or separate planes is not supported; "
            "save it with contiguous strips, as 16-bit greyscale, or as FITS"
        )
    width, height, spp = (_tag_int(tags, tag, path) for tag in (256, 257, 277))
    expected = width * height * spp * 2
    data = _strip_bytes(fh, tags, expected, path)
    if len(data) < expected:
        raise ImageReadError(f"{path}: TIFF file is truncated ({len(data)} of {expected} bytes)")
    fh.seek(0)
    dtype = np.dtype("<u2") if fh.read(2) == b"II" else np.dtype(">u2")
    array = np.frombuffer(data[:expected], dtype=dtype).reshape(height, width, spp)
    if _tag_int(tags, 317, path, default=1) == 2:  # horizontal differencing: undo by a wrapping running sum
        array = np.cumsum(array.astype(np.uint16), axis=1, dtype=np.uint16)
    return array.astype(np.uint16)
