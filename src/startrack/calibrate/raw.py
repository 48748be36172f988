"""Camera RAW files (CR2, NEF, ARW, DNG, ...) through ``rawpy`` (LibRaw), without demosaicing.

A RAW file holds one count per photosite under a colour filter (the Bayer mosaic). For star
positions the honest image is the mosaic reduced cell by cell: each 2 x 2 cell (R, G, G, B in some
order) becomes one pixel, either the **sum** of its four counts (the colour rule of
:mod:`startrack.io.channels`: counts stay counts) or one colour (``"r"``, ``"g"`` = the sum of
the two greens, ``"b"``; seed 003 used the green channel of its phone, the best SNR). The result
has half the resolution: pixel (i, j) of the reduced image is centred on the full-resolution
position ``(2 i + 0.5, 2 j + 0.5)`` (our convention, pixel centres) - use :func:`full_resolution_xy`
to go back. The black level is subtracted; nothing is scaled.

``rawpy`` is imported only when a RAW file is read (``pip install rawpy``).
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ImageReadError, InvalidInputError
from ..io.image import Image

_COLOURS = {"r": (0,), "g": (1, 3), "b": (2,)}


def bayer_cells(mosaic: NDArray, pattern: NDArray, channel: str | None = None) -> NDArray[np.int64]:
    """Reduce a Bayer mosaic (H, W) to cells (H // 2, W // 2).

    Parameters
    ----------
    mosaic : ndarray (H, W)
        Counts, black level already removed (may be negative from noise).
    pattern : ndarray (2, 2) of int
        Colour index of each site of a cell, LibRaw's convention: 0 R, 1 G, 2 B, 3 the second G.
    channel : {None, "r", "g", "b"}
        None: the sum of the four sites; else that colour (two sites summed for "g").
    """
    key = None if channel is None else str(channel).lower()
    if key is not None and key not in _COLOURS:
        raise InvalidInputError(f"channel must be None, 'r', 'g' or 'b', got {channel!r}")
    pattern = np.asarray(pattern)
    if pattern.shape != (2, 2):
        raise InvalidInputError(f"pattern must be a 2 x 2 array of colour indices, got shape {pattern.shape}")
    h, w = (mosaic.shape[0] // 2) * 2, (mosaic.shape[1] // 2) * 2
    m = np.asarray(mosaic[:h, :w], dtype=np.int64)
    out = np.zeros((h // 2, w // 2), dtype=np.int64)
    for dy in range(2):
        for dx in range(2):
            if key is None or pattern[dy, dx] in _COLOURS[key]:
                out += m[dy::2, dx::2]
    return out


def full_resolution_xy(x: ArrayLike, y: ArrayLike) -> tuple[NDArray, NDArray]:
    """Positions in a cell-reduced image -> positions in the full-resolution mosaic."""
    return 2.0 * np.asarray(x, float) + 0.5, 2.0 * np.asarray(y, float) + 0.5


def read_raw(path: str | os.PathLike, channel: str | None = None) -> Image:
    """Read a camera RAW file as a cell-reduced single-channel :class:`~startrack.io.Image`.

    The header holds ``Model``, ``ExposureTime`` and ``DateTimeOriginal`` (EXIF format) when
    LibRaw reports them; ``raw_cells`` = True marks the half-resolution geometry.
    """
    try:
        import rawpy
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError("RAW files need rawpy: pip install rawpy") from None
    try:
        with rawpy.imread(os.fspath(path)) as raw:
            mosaic = raw.raw_image_visible.astype(np.int64) - np.asarray(raw.black_level_per_channel).mean()
            data = bayer_cells(np.round(mosaic).astype(np.int64), raw.raw_pattern, channel)
            header = {"raw_cells": True, "Model": getattr(raw, "camera_model", "")}
    except (rawpy.LibRawError, OSError) as exc:
        raise ImageReadError(f"{path}: not a readable RAW file ({exc})") from exc
    return Image(data=data, header=header, bit_depth=16, colour=True)
