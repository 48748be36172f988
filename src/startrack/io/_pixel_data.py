"""Whether a PNG's or a JPEG's pixel data are complete, when the file's structure says nothing.

A file cut short and then closed again (a PNG whose chunks are whole but whose IDAT data end after
10 of 1,024 rows; a JPEG cut to a third with its end marker put back) decodes in Pillow without
an error: the missing rows are left black, or a JPEG's missing blocks grey. So:

* **PNG**: the IDAT stream is inflated here (the output counted, not kept) and must give every
  row the IHDR declares (:func:`png_missing_data`).
* **JPEG, one scan** (baseline and extended sequential, Huffman coded: what cameras write): the
  file is decoded from :func:`probe_stream`, its bytes up to the end marker with the end marker
  replaced by bytes that are not a marker. A scan that holds every block decodes exactly as before
  (the data after it are never needed); one that stops early makes the decoder ask for more data,
  which Pillow reports as a truncated file.
* **JPEG, several scans** (progressive, or one scan per colour): every component, and for a
  progressive file every coefficient at full precision, must be coded by some scan
  (:meth:`JpegLayout.missing_scans`); a file cut before its last scan lacks some. A cut inside the
  last scan (which in a progressive file only refines the coefficients' lowest bits) is not seen.
"""

from __future__ import annotations

import io
import struct
import zlib
from dataclasses import dataclass, field
from typing import BinaryIO

import numpy as np

_CHUNK = 1 << 20
"""Bytes read at a time (memory stays bounded whatever the file's size)."""

# --- PNG -------------------------------------------------------------------------------------
_PNG_CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}
"""Samples per pixel of each PNG colour type."""
_ADAM7 = ((0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2))
"""The seven passes of an interlaced PNG: first column, first row, column step, row step."""


def png_data_size(width: int, height: int, bit_depth: int, colour_type: int, interlaced: bool) -> int:
    """Bytes the inflated IDAT stream of such a PNG holds: every row of every pass, each with its
    filter-type byte (PNG specification, sections 7.2 and 8.2)."""
    pixel_bits = bit_depth * _PNG_CHANNELS.get(colour_type, 1)
    passes = _ADAM7 if interlaced else ((0, 0, 1, 1),)
    total = 0
    for x0, y0, dx, dy in passes:
        columns, rows = max(0, -(-(width - x0) // dx)), max(0, -(-(height - y0) // dy))
        if columns and rows:
            total += rows * (1 + (columns * pixel_bits + 7) // 8)
    return total


def png_chunks(fh: BinaryIO):
    """(type, length) of each chunk of a PNG file, with ``fh`` at the chunk's data; stops at IEND
    or where the file ends."""
    fh.seek(8)
    while True:
        head = fh.read(8)
        if len(head) < 8:
            return
        length, kind = struct.unpack(">I4s", head)
        start = fh.tell()
        yield kind, length
        if kind == b"IEND":
            return
        fh.seek(start + length + 4)  # the data and the CRC


def _inflated_size(fh: BinaryIO, length: int, inflater, limit: int) -> int:
    """Bytes that ``length`` bytes of ``fh`` add to the inflated stream, counted up to ``limit``."""
    count = 0
    while length > 0 and count < limit and not inflater.eof:
        data = fh.read(min(length, _CHUNK))
        if not data:
            break
        length -= len(data)
        while data and count < limit:
            count += len(inflater.decompress(data, min(_CHUNK, limit - count)))
            data = inflater.unconsumed_tail
    return count


def png_missing_data(fh: BinaryIO) -> str | None:
    """What is missing from a PNG's image data (as the end of a sentence), or None when its IDAT
    stream inflates to every row the IHDR declares.

    The PNG's structure was already read by Pillow; a file whose structure this does not follow
    (no IHDR first) is passed over (None).
    """
    expected = inflated = 0
    inflater = zlib.decompressobj()
    try:
        for kind, length in png_chunks(fh):
            if kind == b"IHDR" and length >= 13:
                width, height, bits, colour, _, _, interlace = struct.unpack(">IIBBBBB", fh.read(13))
                expected = png_data_size(width, height, bits, colour, interlace == 1)
            elif kind == b"IDAT" and expected:
                inflated += _inflated_size(fh, length, inflater, expected - inflated)
    except zlib.error as exc:
        return f"its image data cannot be inflated: {exc}"
    if inflated < expected:
        return f"its image data stop after {inflated:,} of the {expected:,} bytes its rows need"
    return None


# --- JPEG ------------------------------------------------------------------------------------
_SOF = frozenset({0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF})
"""Start-of-frame markers (ITU T.81 table B.1)."""
_PROGRESSIVE = frozenset({0xC2, 0xC6, 0xCA, 0xCE})
_HUFFMAN_SEQUENTIAL = frozenset({0xC0, 0xC1})
_STANDALONE = frozenset({0x01, *range(0xD0, 0xD8)})
"""Markers without a length field (TEM, RST0-7)."""
_PAD = b"\xff\x00" * 16
"""What replaces the end marker in :func:`probe_stream`: 128 one-bits of entropy data, not a marker,
enough for libjpeg's look-ahead (57 bits) after the last block; all-ones is no Huffman code, so a
scan cut short cannot decode its missing blocks from it."""


@dataclass
class JpegLayout:
    """The frame and scans of a JPEG file's first image (its markers, not its pixels).

    Attributes
    ----------
    frame : int
        The start-of-frame marker (0xC0 baseline, 0xC2 progressive, ...).
    components : tuple of int
        The frame's component identifiers.
    scans : list of (components, Ss, Se, Al)
        Each scan's components, spectral selection and successive-approximation low bit.
    end : int
        Offset of the end-of-image marker that closes the image.
    """

    frame: int
    components: tuple[int, ...]
    scans: list[tuple[tuple[int, ...], int, int, int]] = field(default_factory=list)
    end: int = 0

    @property
    def single_scan(self) -> bool:
        """True for a Huffman-coded sequential image in one scan (what :func:`probe_stream` checks)."""
        return self.frame in _HUFFMAN_SEQUENTIAL and len(self.scans) == 1

    def missing_scans(self) -> str | None:
        """What the scans leave uncoded (as the end of a sentence), or None when they code every
        component (and, progressive, every coefficient to its last bit)."""
        if self.frame in _PROGRESSIVE:
            needed = {(c, k) for c in self.components for k in range(64)}
            done = {(c, k) for comps, ss, se, al in self.scans if al == 0 for c in comps for k in range(ss, se + 1)}
        else:
            needed = {(c, 0) for c in self.components}
            done = {(c, 0) for comps, *_ in self.scans for c in comps}
        if needed <= done:
            return None
        return f"its {len(self.scans)} scans end before every part of the image is coded"


def _marker(fh: BinaryIO) -> int | None:
    """The code of the marker at ``fh`` (fill bytes skipped), None if there is none."""
    if fh.read(1) != b"\xff":
        return None
    code = b"\xff"
    while code == b"\xff":
        code = fh.read(1)
    return code[0] if code else None


def _entropy_end(fh: BinaryIO) -> int | None:
    """Offset of the marker that ends the entropy-coded data starting at ``fh`` (0xFF followed
    by a byte other than 0x00, 0xFF or a restart code), None if the file ends first."""
    base, carry = fh.tell(), b""
    while block := fh.read(_CHUNK):
        data = np.frombuffer(carry + block, np.uint8)
        at = np.flatnonzero(data[:-1] == 0xFF)
        code = data[at + 1]
        hits = at[(code != 0) & (code != 0xFF) & ((code < 0xD0) | (code > 0xD7))]
        if hits.size:
            return base + int(hits[0])
        base, carry = base + data.size - 1, bytes(data[-1:])
    return None


def _scan_header(segment: bytes) -> tuple[tuple[int, ...], int, int, int]:
    count = segment[0]
    components = tuple(segment[1 + 2 * i] for i in range(count))
    ss, se, approximation = segment[1 + 2 * count:4 + 2 * count]
    return components, ss, se, approximation & 0x0F


def jpeg_layout(fh: BinaryIO) -> JpegLayout | None:
    """The frame and scans of the JPEG image in ``fh``, or None when its markers cannot be
    followed to an end-of-image marker (Pillow's own decoding then says what is wrong)."""
    fh.seek(2)  # after SOI
    layout: JpegLayout | None = None
    while (code := _marker(fh)) is not None:
        if code == 0xD9:
            if layout is not None:
                layout.end = fh.tell() - 2
            return layout
        if code in _STANDALONE:
            continue
        size = fh.read(2)
        segment = fh.read(int.from_bytes(size, "big") - 2) if len(size) == 2 else b""
        try:
            if code in _SOF:
                layout = JpegLayout(code, tuple(segment[6 + 3 * i] for i in range(segment[5])))
            elif code == 0xDA and layout is not None:
                layout.scans.append(_scan_header(segment))
                end = _entropy_end(fh)
                if end is None:
                    return None
                fh.seek(end)
        except (IndexError, ValueError):  # a segment shorter than its fields
            return None
    return None


class _Probe(io.RawIOBase):
    """The first ``size`` bytes of ``fh`` followed by ``tail``, as a read-only file."""

    def __init__(self, fh: BinaryIO, size: int, tail: bytes) -> None:
        super().__init__()
        self._fh, self._size, self._tail, self._pos = fh, size, tail, 0

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def tell(self) -> int:
        return self._pos

    def seek(self, offset: int, whence: int = io.SEEK_SET) -> int:
        origin = {io.SEEK_SET: 0, io.SEEK_CUR: self._pos, io.SEEK_END: self._size + len(self._tail)}[whence]
        self._pos = max(0, origin + offset)
        return self._pos

    def readinto(self, buffer) -> int:
        view = memoryview(buffer).cast("B")
        if self._pos < self._size:
            self._fh.seek(self._pos)
            data = self._fh.read(min(len(view), self._size - self._pos))
        else:
            start = self._pos - self._size
            data = self._tail[start:start + len(view)]
        view[:len(data)] = data
        self._pos += len(data)
        return len(data)


def probe_stream(fh: BinaryIO, layout: JpegLayout) -> BinaryIO:
    """The JPEG file in ``fh`` up to its end marker, with the end marker replaced by :data:`_PAD`
    (module docstring): decoding it fails as truncated exactly when the one scan ends early."""
    return io.BufferedReader(_Probe(fh, layout.end, _PAD))
