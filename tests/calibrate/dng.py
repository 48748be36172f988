"""A minimal uncompressed Bayer DNG (TIFF tags written by hand) for the RAW reader's tests.

One IFD, one strip of 16-bit little-endian counts, the tags LibRaw needs for a CFA image
(DNG spec 1.4: PhotometricInterpretation 32803, CFARepeatPatternDim, CFAPattern, DNGVersion,
UniqueCameraModel, BlackLevel, WhiteLevel, ColorMatrix1, AsShotNeutral) plus the EXIF exposure
time and original date, which LibRaw also reads from IFD 0.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

_SHORT, _LONG, _RATIONAL, _SRATIONAL, _ASCII, _BYTE = 3, 4, 5, 10, 2, 1
_FORMATS = {_BYTE: "B", _ASCII: "B", _SHORT: "H", _LONG: "I", _RATIONAL: "II", _SRATIONAL: "ii"}
_CFA = {"r": 0, "g": 1, "b": 2}


def _ratios(values, denominator: int = 10000) -> list[int]:
    out = []
    for v in values:
        out += [round(v * denominator), denominator]
    return out


def _tags(width: int, height: int, pattern: str, black: tuple[int, ...], white: int, exposure_s: float,
          date: str, data_offset: int) -> list[tuple[int, int, list[int]]]:
    def text(s: str) -> list[int]:
        return list(s.encode("ascii")) + [0]

    return [
        (254, _LONG, [0]), (256, _LONG, [width]), (257, _LONG, [height]), (258, _SHORT, [16]),
        (259, _SHORT, [1]), (262, _SHORT, [32803]), (271, _ASCII, text("Startrack")),
        (272, _ASCII, text("Test DNG")),
        (306, _ASCII, text(date)), (273, _LONG, [data_offset]), (274, _SHORT, [1]),
        (277, _SHORT, [1]), (278, _LONG, [height]), (279, _LONG, [2 * width * height]),
        (284, _SHORT, [1]), (33421, _SHORT, [2, 2]), (33422, _BYTE, [_CFA[c] for c in pattern]),
        (33434, _RATIONAL, _ratios([exposure_s])), (36867, _ASCII, text(date)),
        (50706, _BYTE, [1, 4, 0, 0]), (50708, _ASCII, text("Startrack Test DNG")),
        (50713, _SHORT, [2, 2]), (50714, _LONG, list(black)), (50717, _LONG, [white]),
        (50721, _SRATIONAL, _ratios([0.6722, -0.1867, -0.0606, -0.4414, 1.2196, 0.2423,
                                     -0.0935, 0.1762, 0.6271])),
        (50728, _RATIONAL, _ratios([0.5, 1.0, 0.7])), (50778, _SHORT, [21]),
    ]


def _ifd(tags: list[tuple[int, int, list[int]]]) -> tuple[bytes, bytes]:
    """IFD 0 (at offset 8) and the values too long for their entries (stored right after it)."""
    extra_at = 8 + 2 + 12 * len(tags) + 4
    entries, extra = [], b""
    for tag, kind, values in tags:
        payload = struct.pack("<" + _FORMATS[kind][0] * len(values), *values)
        count = len(values) // len(_FORMATS[kind])
        if len(payload) <= 4:
            entries.append(struct.pack("<HHI", tag, kind, count) + payload.ljust(4, b"\0"))
        else:
            entries.append(struct.pack("<HHII", tag, kind, count, extra_at + len(extra)))
            extra += payload + b"\0" * (len(payload) % 2)
    return struct.pack("<H", len(tags)) + b"".join(entries) + b"\0" * 4, extra


def write_dng(path: str | Path, mosaic: np.ndarray, *, pattern: str = "rggb", black=(0, 0, 0, 0),
              white: int = 65535, exposure_s: float = 1.0, date: str = "2024:01:01 00:00:00") -> Path:
    """Write ``mosaic`` (H, W) counts (black level included) as a Bayer DNG with ``pattern``
    (the colours of a 2 x 2 cell read row by row, e.g. "rggb") and ``black``, the black level of
    each site of a cell in the same order."""
    mosaic = np.ascontiguousarray(mosaic, dtype="<u2")
    height, width = mosaic.shape
    ifd, extra = _ifd(_tags(width, height, pattern, black, white, exposure_s, date, 0))
    data_offset = 8 + len(ifd) + len(extra)
    ifd, extra = _ifd(_tags(width, height, pattern, black, white, exposure_s, date, data_offset))
    Path(path).write_bytes(b"II*\0" + struct.pack("<I", 8) + ifd + extra + mosaic.tobytes())
    return Path(path)
