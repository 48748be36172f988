"""XISF images: PixInsight's format, which N.I.N.A. and Siril write too.

Read from the published specification (XISF 1.0, https://pixinsight.com/doc/docs/XISF-1.0-spec/
XISF-1.0-spec.html). A monolithic file starts with ``XISF0100``, the length of its XML header
(uint32, little-endian) and four reserved bytes; the header names each image's ``geometry``
(``width:height:channels``), ``sampleFormat``, ``pixelStorage`` (``Planar``: one channel after
the other, the default; ``Normal``: interleaved), ``byteOrder`` and where its pixels are: a block
attached to the file (``attachment:position:size``, the position counted from the file's start),
or in the header itself (``inline:base64`` / ``inline:hex`` text, or an ``embedded`` ``Data``
element). A block may be compressed (``compression="codec:size[:item size]"``; zlib, LZ4, LZ4HC
or Zstandard, ``+sh`` when its bytes were shuffled by item, and ``subblocks`` when it was cut into
separately compressed pieces) and carry a ``checksum`` (SHA-1, SHA-256 or SHA-512 of the block as
stored), which is checked.

The first image is read, rows top first as stored (XISF has no bottom-up convention). Its
``FITSKeyword`` elements become the header, as a FITS file's cards do; an ``Observation:Time:Start``
property stands in for a missing ``DATE-OBS``, and a ``ColorFilterArray`` element for ``BAYERPAT``
(the mosaic is then read as a FITS one is, :mod:`startrack.io._mosaic`). zlib is Python's own;
LZ4 and Zstandard blocks need ``lz4`` and ``zstandard`` (``pip install 'startrack[xisf]'``), and
a file that needs one that is missing is refused with that advice. Distributed XISF (``.xish``
headers with blocks in other files), images of more than two dimensions and complex samples are
refused with a message saying so.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import struct
import xml.etree.ElementTree as ET
import zlib
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from ..errors import ImageReadError
from ._limits import check_image_size

SIGNATURE = b"XISF0100"
"""The first bytes of a monolithic XISF 1.0 file."""
PREAMBLE_BYTES = 16
"""Signature, header length and reserved field."""
MAX_HEADER_BYTES = 1 << 28
"""The longest XML header read (256 MiB: inline thumbnails and properties can make it long)."""
NAMESPACE = "{http://www.pixinsight.com/xisf}"
MAX_CHANNELS = 4

SAMPLE_TYPES = {"UInt8": "u1", "UInt16": "u2", "UInt32": "u4", "UInt64": "u8", "Float32": "f4", "Float64": "f8"}
"""XISF sample formats read, and their numpy types (without byte order)."""
CHECKSUMS = {"sha-1": "sha1", "sha1": "sha1", "sha-256": "sha256", "sha256": "sha256", "sha-512": "sha512",
             "sha512": "sha512"}
"""Checksum algorithms of the specification checked, and their hashlib names."""


def is_xisf(head: bytes) -> bool:
    """Whether a file's first bytes are a monolithic XISF 1.0 signature."""
    return head.startswith(SIGNATURE)


def read_xisf(path: Path, max_pixels: int | None = None) -> tuple[NDArray, dict[str, Any], int]:
    """The first image of an XISF file (module docstring).

    Returns
    -------
    data : ndarray, shape (H, W) or (H, W, C)
        The samples in their own type (unsigned integers or floats), channels last.
    header : dict
        The image's FITS keywords (keyword -> value), with ``DATE-OBS`` and ``BAYERPAT`` from the
        XISF properties when the keywords do not give them.
    bit_depth : int
        Bits per sample.

    Raises
    ------
    ImageReadError
        If the file is truncated or damaged, or holds no image that can be read; the message
        names the file and the problem.
    """
    with open(path, "rb") as fh:
        image = _first_image(_header_root(fh, path), path)
        width, height, channels = _geometry(image, path)
        check_image_size(width, height, max_pixels, path)
        dtype = _sample_type(image, path)
        stored = _stored_block(fh, image, path)
    expected = width * height * channels * dtype.itemsize
    raw = _decoded(stored, image, expected, path)
    if len(raw) != expected:
        raise ImageReadError(f"{path}: the image's pixel block holds {len(raw)} bytes; its geometry "
                             f"{width}:{height}:{channels} of {image.get('sampleFormat')} needs {expected}")
    data = _arranged(np.frombuffer(raw, dtype), image.get("pixelStorage", "Planar"), height, width, channels, path)
    return data, _header(image), dtype.itemsize * 8


def xisf_size(path: Path) -> tuple[int, int]:
    """Width and height of an XISF file's first image, from its header alone."""
    with open(path, "rb") as fh:
        width, height, _ = _geometry(_first_image(_header_root(fh, path), path), path)
    return width, height


def _header_root(fh: BinaryIO, path: Path) -> ET.Element:
    """The XML header of an open XISF file, parsed."""
    preamble = fh.read(PREAMBLE_BYTES)
    if len(preamble) < PREAMBLE_BYTES or not is_xisf(preamble):
        raise ImageReadError(f"{path}: not a monolithic XISF 1.0 file (it must start with {SIGNATURE!r}; a "
                             "distributed XISF header, .xish, is not read)")
    (length,) = struct.unpack("<I", preamble[8:12])
    if length > MAX_HEADER_BYTES:
        raise ImageReadError(f"{path}: its XISF header claims {length:,} bytes (at most {MAX_HEADER_BYTES:,} are read)")
    text = fh.read(length)
    if len(text) < length:
        raise ImageReadError(f"{path}: truncated XISF file: its header claims {length:,} bytes, {len(text):,} follow")
    try:
        return ET.fromstring(text.rstrip(b"\0"))
    except ET.ParseError as exc:
        raise ImageReadError(f"{path}: its XISF header is not well-formed XML ({exc})") from exc


def _first_image(root: ET.Element, path: Path) -> ET.Element:
    image = root.find(f"{NAMESPACE}Image")
    image = root.find("Image") if image is None else image
    if image is None:
        raise ImageReadError(f"{path}: the XISF file holds no Image element")
    return image


def _geometry(image: ET.Element, path: Path) -> tuple[int, int, int]:
    """Width, height and channel count of a 2-D image's ``geometry`` attribute."""
    text = image.get("geometry", "")
    try:
        sizes = [int(part) for part in text.split(":")]
    except ValueError:
        sizes = []
    if len(sizes) != 3 or min(sizes) < 1:
        raise ImageReadError(f"{path}: XISF image geometry {text!r} is not width:height:channels of positive "
                             "integers (images of more than two dimensions are not read)")
    if sizes[2] > MAX_CHANNELS:
        raise ImageReadError(f"{path}: XISF image of {sizes[2]} channels; 1 (grey) to {MAX_CHANNELS} (RGB and "
                             "alpha) are read")
    return sizes[0], sizes[1], sizes[2]


def _sample_type(image: ET.Element, path: Path) -> np.dtype:
    name = image.get("sampleFormat", "")
    if name not in SAMPLE_TYPES:
        raise ImageReadError(f"{path}: XISF sample format {name!r} is not read; valid: {', '.join(SAMPLE_TYPES)}")
    order = image.get("byteOrder", "little")
    if order not in ("little", "big"):
        raise ImageReadError(f"{path}: XISF byte order {order!r} is neither 'little' nor 'big'")
    return np.dtype(("<" if order == "little" else ">") + SAMPLE_TYPES[name])


def _stored_block(fh: BinaryIO, image: ET.Element, path: Path) -> bytes:
    """The image's pixel block as stored (compressed or not), checked against its checksum."""
    kind, _, rest = image.get("location", "").partition(":")
    if kind == "attachment":
        stored = _attached(fh, rest, path)
    elif kind == "inline":
        stored = _text_data(image.text or "", rest, path)
    elif kind == "embedded":
        data = image.find(f"{NAMESPACE}Data")
        data = image.find("Data") if data is None else data
        if data is None:
            raise ImageReadError(f"{path}: XISF image location is 'embedded' but it has no Data element")
        stored = _text_data(data.text or "", data.get("encoding", ""), path)
    else:
        raise ImageReadError(f"{path}: XISF image location {image.get('location')!r} is not read; valid: "
                             "attachment:POSITION:SIZE, inline:base64, inline:hex, embedded")
    _check_sum(stored, image.get("checksum"), path)
    return stored


def _attached(fh: BinaryIO, where: str, path: Path) -> bytes:
    try:
        position, size = (int(part) for part in where.split(":"))
    except ValueError:
        raise ImageReadError(f"{path}: XISF attachment {where!r} is not POSITION:SIZE") from None
    fh.seek(position)
    block = fh.read(size)
    if len(block) < size:
        raise ImageReadError(f"{path}: truncated XISF file: the image's block of {size:,} bytes at {position:,} "
                             f"ends after {len(block):,}")
    return block


def _text_data(text: str, encoding: str, path: Path) -> bytes:
    try:
        if encoding == "base64":
            return base64.b64decode("".join(text.split()), validate=True)
        if encoding == "hex":
            return bytes.fromhex("".join(text.split()))
    except (binascii.Error, ValueError) as exc:
        raise ImageReadError(f"{path}: the XISF image's {encoding} data cannot be decoded ({exc})") from exc
    raise ImageReadError(f"{path}: XISF data encoding {encoding!r} is not base64 or hex")


def _check_sum(stored: bytes, checksum: str | None, path: Path) -> None:
    if not checksum:
        return
    algorithm, _, digest = checksum.partition(":")
    if algorithm.lower() not in CHECKSUMS:
        return  # an algorithm not checked here (SHA-3): the block is taken as it is
    if hashlib.new(CHECKSUMS[algorithm.lower()], stored).hexdigest() != digest.strip().lower():
        raise ImageReadError(f"{path}: the XISF image's block does not match its {algorithm} checksum (the file is "
                             "damaged)")


def _decoded(stored: bytes, image: ET.Element, expected: int, path: Path) -> bytes:
    """The block decompressed and unshuffled (``stored`` itself when it is not compressed). The
    size it declares must be the ``expected`` bytes of the image's geometry, and no codec is let
    write more: a small block cannot unpack to more memory than the image's size allows."""
    spec = image.get("compression")
    if not spec:
        return stored
    parts = spec.split(":")
    codec, shuffled = parts[0].removesuffix("+sh"), parts[0].endswith("+sh")
    try:
        size = int(parts[1])
        item = int(parts[2]) if shuffled else 1
    except (IndexError, ValueError):
        raise ImageReadError(f"{path}: XISF compression {spec!r} is not CODEC:SIZE or CODEC+sh:SIZE:ITEM") from None
    if size != expected:
        raise ImageReadError(f"{path}: XISF compression {spec!r} declares {size:,} bytes; the image's geometry "
                             f"needs {expected:,}")
    pieces = _subblocks(image.get("subblocks"), stored, size, path)
    raw = b"".join(_decompress(codec, piece, out_size, path) for piece, out_size in pieces or [(stored, size)])
    if len(raw) != size:
        raise ImageReadError(f"{path}: the XISF image's block decompressed to {len(raw):,} bytes, not {size:,}")
    return _unshuffled(raw, item) if item > 1 else raw


def _subblocks(spec: str | None, stored: bytes, size: int, path: Path) -> list[tuple[bytes, int]]:
    """The separately compressed pieces of a block: (compressed bytes, decompressed size); their
    sizes must add up to the block's and to its declared ``size``."""
    if not spec:
        return []
    pieces, start = [], 0
    try:
        for pair in spec.split(":"):
            packed, unpacked = (int(v) for v in pair.split(","))
            pieces.append((stored[start:start + packed], unpacked))
            start += packed
    except ValueError:
        raise ImageReadError(f"{path}: XISF subblocks {spec!r} are not C,U:C,U:... byte counts") from None
    if start != len(stored) or sum(unpacked for _, unpacked in pieces) != size:
        raise ImageReadError(f"{path}: XISF subblocks {spec!r} do not add up to the block's {len(stored):,} bytes "
                             f"and its {size:,} decompressed")
    return pieces


def _decompress(codec: str, data: bytes, size: int, path: Path) -> bytes:
    try:
        if codec == "zlib":
            return zlib.decompressobj().decompress(data, size)
        if codec in ("lz4", "lz4hc"):
            from lz4 import block  # the "xisf" extra

            return block.decompress(data, uncompressed_size=size)
        if codec == "zstd":
            import zstandard  # the "xisf" extra

            return zstandard.ZstdDecompressor().stream_reader(data).read(size)
    except ImportError as exc:
        raise ImageReadError(f"{path}: its pixels are compressed with {codec}, which needs the {exc.name} package: "
                             "pip install 'startrack[xisf]'") from exc
    except Exception as exc:  # each codec raises its own error for a damaged stream
        raise ImageReadError(f"{path}: the XISF image's {codec} block cannot be decompressed ({exc})") from exc
    raise ImageReadError(f"{path}: XISF compression codec {codec!r} is not read; valid: zlib, lz4, lz4hc, zstd "
                         "(each also +sh)")


def _unshuffled(raw: bytes, item: int) -> bytes:
    """Undo byte shuffling: the first bytes of all items, then their second bytes, ...; the bytes
    past the last whole item are stored as they are."""
    count = len(raw) // item
    body = np.frombuffer(raw, np.uint8, count * item).reshape(item, count).T
    return body.tobytes() + raw[count * item:]


def _arranged(samples: NDArray, storage: str, height: int, width: int, channels: int, path: Path) -> NDArray:
    """Samples (H * W * C,) as an image (H, W) or (H, W, C)."""
    if storage == "Planar":
        data = samples.reshape(channels, height, width).transpose(1, 2, 0)
    elif storage == "Normal":
        data = samples.reshape(height, width, channels)
    else:
        raise ImageReadError(f"{path}: XISF pixel storage {storage!r} is neither 'Planar' nor 'Normal'")
    return data[..., 0] if channels == 1 else data


def _header(image: ET.Element) -> dict[str, Any]:
    """The image's FITS keywords, with DATE-OBS and BAYERPAT from XISF elements where missing."""
    header: dict[str, Any] = {}
    implied: dict[str, Any] = {}
    for card in image.iter():
        tag = card.tag.removeprefix(NAMESPACE)
        if tag == "FITSKeyword" and card.get("name"):
            name = card.get("name", "").strip().upper()
            if name in ("COMMENT", "HISTORY"):
                header.setdefault(name, []).append(card.get("comment", ""))
            else:
                header[name] = keyword_value(card.get("value", ""))
        elif tag == "Property" and card.get("id") == "Observation:Time:Start" and (start := _utc(card.get("value"))):
            implied["DATE-OBS"] = start
        elif tag == "ColorFilterArray" and card.get("pattern"):
            implied["BAYERPAT"] = card.get("pattern")
    return {**implied, **header}


def _utc(text: str | None) -> str | None:
    """An ISO 8601 time point as a UTC ``DATE-OBS`` (None when it is not one)."""
    try:
        moment = datetime.fromisoformat((text or "").strip())
    except ValueError:
        return None
    if moment.tzinfo is not None:
        moment = moment.astimezone(UTC).replace(tzinfo=None)
    return moment.isoformat()


def keyword_value(text: str) -> Any:
    """A FITS keyword's value as XISF writes it (the value field of a FITS card): a quoted
    string (``''`` inside for a quote), ``T`` / ``F``, an integer or a real (``D`` exponents too);
    None when empty."""
    value = text.strip()
    if value.startswith("'"):
        end = value.rfind("'")
        return value[1:end].replace("''", "'").rstrip() if end > 0 else value[1:].rstrip()
    if value in ("T", "F"):
        return value == "T"
    for parse in (int, lambda v: float(v.replace("D", "E").replace("d", "e"))):
        try:
            return parse(value)
        except ValueError:
            pass
    return value or None
