"""Camera RAW files (CR2, NEF, ARW, RAF, DNG, ...) through ``rawpy`` (LibRaw), without demosaicing.

A RAW file holds one count per photosite under a colour filter (a Bayer mosaic, or Fujifilm's
6 x 6 X-Trans); a few hold a monochrome sensor's counts, or three colour planes already
interpolated (a linear DNG, as phones write "ProRAW"). Two readings:

* :func:`read_raw_plane`, what :func:`startrack.io.read_image` (and so every solve) does: the mosaic
  at full resolution, its hot sites replaced and its colours evened out by the colour-neutral
  3 x 3 kernel of :mod:`startrack.io._mosaic` (or site by site, :mod:`startrack.io._cfa`, for a
  pattern other than 2 x 2), as for a one-shot-colour camera's FITS frame.
  Positions and a WCS refer to the sensor's pixels. On the simulated frames of
  ``benchmarks/bayer_fits.py`` it finds 44 % and 48 % more stars than the cell sums below (PSF sd
  1.0 and 1.6 px), centroids 0.69 and 0.92 times their RMS error; an X-Trans mosaic read site by
  site, 89 % and 88 % of a grey sensor's stars, where its pixels read as grey give 48 % and 44 %.
* :func:`read_raw`, for calibration work that wants whole photosites: the mosaic reduced cell by
  cell. Each 2 x 2 cell (R, G, G, B in some order) becomes one pixel, either the **sum** of its
  four counts (the colour rule of :mod:`startrack.io._channels`: counts stay counts) or one colour
  (``"r"``, ``"g"`` = the sum of the two greens, ``"b"``; Fowler 2013 used the green channel of
  its phone, the best SNR).

The cells have half the resolution. Pixel (i, j) of the reduced image samples the full-resolution
position ``(2 i + ox, 2 j + oy)`` (our convention, pixel centres), where the *origin* ``(ox, oy)``
is the mean position of the sites used inside their cell: (0.5, 0.5) for the sum and for green
(two diagonal sites), but the R or B site itself for one of those, e.g. (0, 0) for R in an RGGB
mosaic - half a full-resolution pixel from the cell centre in x and y. :func:`read_raw` stores it
in the header as ``raw_origin_xy``; :func:`full_resolution_xy` maps positions back with it. The
black level of every site is subtracted in both readings; nothing is scaled.

``rawpy`` is imported only when a RAW file is read (``pip install rawpy``).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ImageReadError, InvalidInputError, require
from ._cfa import mosaic_to_plane, pattern_tile
from ._channels import channel_index, to_single_channel
from ._image import Image
from ._limits import check_image_size
from ._mosaic import BAYER_PATTERNS

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


def cell_origin(pattern: NDArray, channel: str | None = None) -> tuple[float, float]:
    """Mean (x, y) position, inside a 2 x 2 cell, of the sites :func:`bayer_cells` adds for
    ``channel`` (full-resolution pixels from the cell's first site): (0.5, 0.5) for the sum."""
    pattern = np.asarray(pattern)
    if channel is None:
        return 0.5, 0.5
    rows, cols = np.nonzero(np.isin(pattern, _COLOURS[str(channel).lower()]))
    return float(cols.mean()), float(rows.mean())


def full_resolution_xy(x: ArrayLike, y: ArrayLike, origin_xy: tuple[float, float] = (0.5, 0.5)
                       ) -> tuple[NDArray, NDArray]:
    """Positions in a cell-reduced image -> positions (x, y) in the full-resolution mosaic.

    ``origin_xy`` is the image's ``header["raw_origin_xy"]`` (:func:`cell_origin`); the default,
    the cell centre, is right for the sum of the four sites and for green.
    """
    return 2.0 * np.asarray(x, float) + origin_xy[0], 2.0 * np.asarray(y, float) + origin_xy[1]


def read_raw(path: str | os.PathLike, channel: str | None = None, max_pixels: int | None = None) -> Image:
    """Read a camera RAW file as a cell-reduced single-channel :class:`~startrack.io.Image`.

    Parameters
    ----------
    path : path
        Any file LibRaw reads (CR2, NEF, ARW, DNG, ...) with a 2 x 2 Bayer mosaic.
    channel : {None, "r", "g", "b"}
        See :func:`bayer_cells`.
    max_pixels : int, optional
        Largest number of photosites (:mod:`startrack.io._limits`), checked from LibRaw's sizes
        before the mosaic is converted (LibRaw itself unpacks the file when it opens it).

    Returns
    -------
    Image
        ``data`` (H // 2, W // 2) int64 counts above the black level. The header holds
        ``raw_cells`` = True (the half-resolution geometry), ``raw_origin_xy``
        (:func:`full_resolution_xy`), and when LibRaw reports them ``ExposureTime`` (s) and
        ``DateTimeOriginal`` (EXIF format, the camera clock) for :func:`.ground.time_from_header`.
    """
    sensor = _read_sensor(path, max_pixels)
    if sensor.pattern not in BAYER_PATTERNS:
        held = "a monochrome sensor or colour planes" if sensor.pattern is None else f"the pattern {sensor.pattern}"
        raise ImageReadError(f"{path}: cell sums need a 2 x 2 Bayer mosaic, the file holds {held} "
                             "(read_image reads it at full resolution)")
    colours = require(sensor.colours, "the mosaic's colours")
    data = bayer_cells(np.rint(sensor.data).astype(np.int64), colours, channel)
    header = {"raw_cells": True, "raw_origin_xy": cell_origin(colours, channel), **sensor.header}
    return Image(data=data, path=Path(path), header=header, bit_depth=16, colour=True)


def read_raw_plane(path: str | os.PathLike, channel: str | None = None, max_pixels: int | None = None) -> Image:
    """Read a camera RAW file at full resolution, as :func:`startrack.io.read_image` does, so that
    positions and a WCS refer to the sensor's own pixels. By what the sensor recorded:

    * a 2 x 2 Bayer mosaic above its black levels through :func:`._mosaic.mosaic_plane` (hot sites
      replaced, then the colour-neutral 3 x 3 kernel, or one colour's sites interpolated);
    * any other filter array of red, green and blue (Fujifilm's 6 x 6 X-Trans) through
      :func:`._cfa.cfa_plane`, the same colour mix from weights of its own at every site;
    * a monochrome sensor's counts as they are;
    * a linear DNG's three colour planes (an already demosaiced file, as phones write "ProRAW"),
      summed by the colour rule of :mod:`._channels` or one of them.

    Parameters
    ----------
    path, channel, max_pixels
        As for :func:`read_raw`.

    Returns
    -------
    Image
        ``data`` (H, W) float32 counts above the black level (LibRaw's visible area), ``mosaic``
        the filter pattern ("RGGB", ...; the rows of a longer one joined by "/", e.g.
        "GGRGGB/GGBGGR/BRGRBG/GGBGGR/GGRGGB/RBGBRG"; None for a monochrome sensor or a linear
        DNG), and the header of :func:`read_raw` without its cell keys.
    """
    index = channel_index(channel)  # checked before the file is read
    sensor = _read_sensor(path, max_pixels)
    if sensor.pattern is None:
        plane = to_single_channel(sensor.data, index).astype(np.float32, copy=False)
    else:
        try:
            plane = mosaic_to_plane(sensor.data, sensor.pattern, index)
        except InvalidInputError as exc:
            raise ImageReadError(f"{path}: {exc}") from None
    return Image(data=plane, path=Path(path), header=sensor.header, bit_depth=16,
                 colour=sensor.data.ndim == 3 or sensor.pattern is not None, mosaic=sensor.pattern)


_LIBRAW_INDEX = {"R": 0, "G": 1, "B": 2}
"""LibRaw's colour index of each filter letter (its second green, 3, is read as 1)."""


class RawSensor(NamedTuple):
    """What a RAW file's sensor recorded, less each site's black level (float32)."""

    data: NDArray[np.float32]
    """(H, W) counts of a mosaic or a monochrome sensor, or (H, W, 3) R, G, B planes of a linear
    DNG."""
    colours: NDArray[np.intp] | None
    """(P, Q) colour of each site of one period of the mosaic from its first pixel (0 R, 1 G,
    2 B); None for a monochrome sensor or colour planes."""
    pattern: str | None
    """The pattern's letters, row by row (rows joined by "/" beyond 2 x 2); None with ``colours``."""
    header: dict
    """:func:`_exif`."""


def _read_sensor(path: str | os.PathLike, max_pixels: int | None) -> RawSensor:
    """The visible part of what a RAW file's sensor recorded (:class:`RawSensor`)."""
    try:
        import rawpy
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError("RAW files need rawpy: pip install rawpy") from None
    try:
        with rawpy.imread(os.fspath(path)) as raw:
            check_image_size(int(raw.sizes.width), int(raw.sizes.height), max_pixels, path)
            if raw.raw_type == rawpy.RawType.Stack:
                return RawSensor(_colour_planes(raw, path), None, None, _exif(raw))
            black = np.asarray(raw.black_level_per_channel, dtype=np.float32)
            if raw.num_colors == 1:
                return RawSensor(raw.raw_image_visible.astype(np.float32) - black[0], None, None, _exif(raw))
            colours, pattern = _filter_pattern(raw, path)
            sites = np.asarray(raw.raw_colors_visible[: colours.shape[0], : colours.shape[1]])
            mosaic = raw.raw_image_visible.astype(np.float32)
            mosaic -= pattern_tile(black[sites], (0, 0), mosaic.shape)
            return RawSensor(mosaic, colours, pattern, _exif(raw))
    except (rawpy.LibRawError, OSError) as exc:
        raise ImageReadError(f"{path}: not a readable RAW file ({exc})") from exc


def _colour_planes(raw, path) -> NDArray[np.float32]:
    """A linear DNG's planes (LibRaw's "stack" of one value per colour per pixel) above their
    black levels, in the order R, G, B: (H, W, 3) float32."""
    letters = [chr(c) for c in raw.color_desc[: raw.num_colors]]
    if sorted(letters) != ["B", "G", "R"]:
        raise ImageReadError(f"{path}: colour planes {''.join(letters)!r}; only red, green and blue are read")
    order = [letters.index(c) for c in "RGB"]
    black = np.asarray(raw.black_level_per_channel, dtype=np.float32)[order]
    return raw.raw_image_visible[..., order].astype(np.float32) - black


def _filter_pattern(raw, path) -> tuple[NDArray[np.intp], str]:
    """The colour (0 R, 1 G, 2 B) of each site of one period of the mosaic from its visible first
    pixel, (P, Q), and its letters (rows joined by "/" beyond 2 x 2)."""
    period = np.shape(raw.raw_pattern) if raw.raw_pattern is not None else (0, 0)
    sites = np.asarray(raw.raw_colors_visible[: period[0], : period[-1]]) if len(period) == 2 else np.zeros((0, 0))
    letters = np.array([[chr(raw.color_desc[i]) for i in row] for row in sites], dtype="U1").reshape(sites.shape)
    if sites.shape != period or set(letters.ravel()) != set(_LIBRAW_INDEX):  # red, green, blue and nothing else
        read = "/".join("".join(row) for row in letters) or "no pattern"
        raise ImageReadError(f"{path}: its sensor's filters read {read!r}, not red, green and blue; startrack reads "
                             "mosaics of R, G and B filters (Bayer, X-Trans), monochrome sensors and linear DNGs")
    colours = np.vectorize(_LIBRAW_INDEX.__getitem__, otypes=[np.intp])(letters)
    rows = ["".join(row) for row in letters]
    return colours, "".join(rows) if colours.shape == (2, 2) else "/".join(rows)


def _exif(raw) -> dict:
    """ExposureTime and DateTimeOriginal from LibRaw (``RawPy.other``, rawpy >= 0.25)."""
    other = getattr(raw, "other", None)
    out: dict = {}
    if other is None:
        return out
    if other.shutter_speed > 0:
        out["ExposureTime"] = float(other.shutter_speed)
    if other.timestamp.year > 1970:  # LibRaw's 0 = unknown; local-time round trip = camera clock
        out["DateTimeOriginal"] = other.timestamp.strftime("%Y:%m:%d %H:%M:%S")
    return out
