"""Minimal uncompressed DNGs (TIFF tags written by hand) for the RAW reader's tests.

One IFD, one strip of 16-bit little-endian counts, the tags LibRaw needs for a CFA image
(DNG spec 1.4: PhotometricInterpretation 32803, CFARepeatPatternDim, CFAPattern, DNGVersion,
UniqueCameraModel, BlackLevel, WhiteLevel, ColorMatrix1, AsShotNeutral) plus the EXIF exposure
time and original date, which LibRaw also reads from IFD 0. The pattern may have any period (a
6 x 6 X-Trans one); :func:`write_linear_dng` writes a LinearRaw image (PhotometricInterpretation
34892) of one or three samples per pixel instead, as phones write demosaiced "ProRAW" files.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import NamedTuple

import numpy as np

_SHORT, _LONG, _RATIONAL, _SRATIONAL, _ASCII, _BYTE = 3, 4, 5, 10, 2, 1
_FORMATS = {_BYTE: "B", _ASCII: "B", _SHORT: "H", _LONG: "I", _RATIONAL: "II", _SRATIONAL: "ii"}
_CFA = {"r": 0, "g": 1, "b": 2, "c": 3, "m": 4, "y": 5}


def _ratios(values, denominator: int = 10000) -> list[int]:
    out = []
    for v in values:
        out += [round(v * denominator), denominator]
    return out


def _tags(width: int, height: int, pattern: str, black: tuple[int, ...], white: int, exposure_s: float,
          date: str, data_offset: int, samples: int = 0, active_area: tuple[int, ...] | None = None
          ) -> list[tuple[int, int, list[int]]]:
    """The IFD's tags: a CFA image of ``pattern`` (rows joined by "/" beyond 2 x 2), or with
    ``samples`` (1 or 3) a LinearRaw one; ``black`` has one value per site of a 2 x 2 cell, or one;
    ``active_area`` (top, left, bottom, right) the part of the sensor that saw light."""
    def text(s: str) -> list[int]:
        return list(s.encode("ascii")) + [0]

    rows = pattern.split("/") if "/" in pattern else [pattern[:2], pattern[2:]]
    layout = [(262, _SHORT, [34892]), (277, _SHORT, [samples])] if samples else \
        [(262, _SHORT, [32803]), (277, _SHORT, [1]), (33421, _SHORT, [len(rows), len(rows[0])]),
         (33422, _BYTE, [_CFA[c] for c in "".join(rows)])]
    per_pixel = max(1, samples)
    if active_area is not None:
        layout.append((50829, _LONG, list(active_area)))
    return sorted([
        (254, _LONG, [0]), (256, _LONG, [width]), (257, _LONG, [height]), (258, _SHORT, [16] * per_pixel),
        (259, _SHORT, [1]), *layout, (271, _ASCII, text("Startrack")),
        (272, _ASCII, text("Test DNG")),
        (306, _ASCII, text(date)), (273, _LONG, [data_offset]), (274, _SHORT, [1]),
        (278, _LONG, [height]), (279, _LONG, [2 * per_pixel * width * height]),
        (284, _SHORT, [1]),
        (33434, _RATIONAL, _ratios([exposure_s])), (36867, _ASCII, text(date)),
        (50706, _BYTE, [1, 4, 0, 0]), (50708, _ASCII, text("Startrack Test DNG")),
        (50713, _SHORT, [2, 2] if len(black) == 4 else [1, 1]), (50714, _LONG, list(black)), (50717, _LONG, [white]),
        (50721, _SRATIONAL, _ratios([0.6722, -0.1867, -0.0606, -0.4414, 1.2196, 0.2423,
                                     -0.0935, 0.1762, 0.6271])),
        (50728, _RATIONAL, _ratios([0.5, 1.0, 0.7])), (50778, _SHORT, [21]),
    ])


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
              white: int = 65535, exposure_s: float = 1.0, date: str = "2024:01:01 00:00:00",
              active_area: tuple[int, int, int, int] | None = None) -> Path:
    """Write ``mosaic`` (H, W) counts (black level included) as a CFA DNG with ``pattern``
    (the colours of a 2 x 2 cell read row by row, e.g. "rggb", or the rows of a longer period
    joined by "/") and ``black``, the black level of each site of a 2 x 2 cell in the same order,
    or one for every site; ``active_area`` (top, left, bottom, right) leaves masked margins."""
    return _write(path, np.asarray(mosaic), _Layout(pattern, tuple(black), white, exposure_s, date, 0, active_area))


def write_linear_dng(path: str | Path, planes: np.ndarray, *, black: int = 0, exposure_s: float = 1.0,
                     date: str = "2024:01:01 00:00:00") -> Path:
    """Write ``planes`` (H, W, 3) R, G, B counts, or (H, W) of a monochrome sensor (black level
    included), as a LinearRaw DNG."""
    planes = np.asarray(planes)
    samples = 1 if planes.ndim == 2 else planes.shape[2]
    return _write(path, planes, _Layout("rggb", (black,), 65535, exposure_s, date, samples, None))


class _Layout(NamedTuple):
    pattern: str
    black: tuple[int, ...]
    white: int
    exposure_s: float
    date: str
    samples: int
    active_area: tuple[int, int, int, int] | None


def _write(path: str | Path, pixels: np.ndarray, layout: _Layout) -> Path:
    """The file: header, IFD 0 with its long values, then the pixels (one strip)."""
    pixels = np.ascontiguousarray(pixels, dtype="<u2")
    height, width = pixels.shape[:2]

    def tags(offset: int) -> list[tuple[int, int, list[int]]]:
        return _tags(width, height, layout.pattern, layout.black, layout.white, layout.exposure_s, layout.date,
                     offset, layout.samples, layout.active_area)

    ifd, extra = _ifd(tags(0))
    ifd, extra = _ifd(tags(8 + len(ifd) + len(extra)))
    Path(path).write_bytes(b"II*\0" + struct.pack("<I", 8) + ifd + extra + pixels.tobytes())
    return Path(path)
