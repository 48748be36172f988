"""The compiled loop of :mod:`startrack.io._png16`: undoing PNG's per-row filters (numba; import
it after :func:`startrack.numba_cache.prepare`)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def unfilter(data, height, stride, bpp, out):
    """Reconstruct the bytes of ``height`` rows of ``stride`` bytes each from the inflated stream
    ``data`` (uint8, ``height * (stride + 1)``: each row's filter-type byte, then its filtered
    bytes) into ``out`` (uint8, (height, stride)), ``bpp`` bytes a pixel (PNG specification,
    section 9). Returns -1, or the first row whose filter type is not 0-4."""
    zero = np.zeros(stride, np.uint8)
    for r in range(height):
        start = r * (stride + 1)
        kind = data[start]
        if kind > 4:
            return r
        _row(data[start + 1: start + 1 + stride], out[r - 1] if r > 0 else zero, out[r], kind, bpp)
    return -1


@njit(cache=True)
def _row(line, up, row, kind, bpp):
    """One row: ``row`` from its filtered bytes ``line``, the row above ``up`` (zeros for the
    first) and filter type ``kind`` (0 None, 1 Sub, 2 Up, 3 Average, 4 Paeth)."""
    n = line.size
    if kind == 0:
        row[:] = line
    elif kind == 1:
        for i in range(n):
            row[i] = (int(line[i]) + (int(row[i - bpp]) if i >= bpp else 0)) & 0xFF
    elif kind == 2:
        for i in range(n):
            row[i] = (int(line[i]) + int(up[i])) & 0xFF
    elif kind == 3:
        for i in range(n):
            left = int(row[i - bpp]) if i >= bpp else 0
            row[i] = (int(line[i]) + (left + int(up[i])) // 2) & 0xFF
    else:
        for i in range(n):
            row[i] = (int(line[i]) + _paeth(int(row[i - bpp]) if i >= bpp else 0, int(up[i]),
                                            int(up[i - bpp]) if i >= bpp else 0)) & 0xFF


@njit(cache=True)
def _paeth(a, b, c):
    """PNG's Paeth predictor (section 9.4): of the left, upper and upper-left bytes, the one
    nearest to left + upper - upper-left (ties in that order)."""
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c
