"""Colour-filter (Bayer) mosaics in FITS files, read at full resolution.

A one-shot-colour astronomy camera (a ZWO, QHY or Player One "MC" model) saves its frames as FITS
files of raw photosites: one count per pixel under a red, green or blue filter, the filters in a
2 x 2 pattern named by the header card ``BAYERPAT`` ("RGGB", "BGGR", "GRBG" or "GBRG"; written by
NINA, SharpCap, ASIAIR, INDI, MaxIm DL). Read as a grey image, such a frame is a checkerboard: the
sky differs from site to site (the filters pass different light, the sky's colour is not the
stars'), every star is cut into a pattern of bright and dark pixels, and the detector suffers. In
``benchmarks/bayer_fits.py`` (simulated 15 deg frames, 10 per case) the mosaic read as grey pixels
gave 64 % and 47 % of the stars a grey sensor's frame gives (PSF sd 1.0 and 1.6 px), their
centroids 1.5 and 1.9 times farther off; with 0.05 % of its pixels hot, 171 false detections per
frame beside 44 stars.

The mosaic is turned into one plane by correlating it with the 3 x 3 kernel
[1, 2, 1] x [1, 2, 1] / 16 (:func:`mosaic_luminance`). Whichever site it is centred on, the kernel
gives the red sites a quarter of its weight, the green ones half and the blue ones a quarter, the
proportions of a whole 2 x 2 cell: every output pixel is the same colour mix, so the checkerboard
goes, and, the kernel being symmetric, it stays at its pixel's position. Unlike the cell sums of
:func:`startrack.io._raw.read_raw` the image keeps its size, so pixel positions, the WCS and
overlays refer to the file's own pixels (camera RAW files are read the same way,
:func:`startrack.io._raw.read_raw_plane`). The kernel blurs by 0.71 px (its standard deviation),
less than the detector's own smoothing; it does not depend on the pattern nor on the row order
(``ROWORDER``).
Hot pixels are replaced first (:func:`without_hot_sites`), since the kernel would make stars of
them. Read so, the same frames gave 88 % and 89 % of the grey sensor's stars, centroids 1.23 and
1.11 times its RMS error, and 3.8 false detections per frame with the hot pixels. Both steps cost 10.5 ms on
a 1024 x 1024 frame and 0.47 s on a 6248 x 4176 one (medians of 30 and 3 runs).

One colour (``channel``) is taken from the sites of that colour alone, interpolated bilinearly in
between (the same kernel over the masked mosaic, divided by that colour's share of it). That needs
the pattern: it is read as starting at the array's first pixel (FITS pixel 1, 1), shifted by
``XBAYROFF`` and ``YBAYROFF`` columns and rows when the header gives them.

A FITS file without ``BAYERPAT`` is taken for a mosaic when the levels of the four sites of its
2 x 2 cells form a checkerboard (:func:`site_pattern`): half the difference between the sums of the
two diagonals (R + B against the two greens) exceeds :data:`MIN_CHECKERBOARD_SIGMA` times the pixel
noise (and two counts, for a frame of whole counts). The sky does that on a colour sensor, whose
raw green sites take in about twice what the red and blue ones do; a gradient across the frame,
however steep, does not (it shifts both diagonals alike), nor does a frame without noise. Its
colour cannot be picked.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError

BAYER_PATTERNS = ("RGGB", "BGGR", "GRBG", "GBRG")
"""The 2 x 2 colour-filter patterns ``BAYERPAT`` may name: the filters of the cell's first row,
then of its second."""

MIN_CHECKERBOARD_SIGMA = 2.0
"""A FITS frame without ``BAYERPAT`` is read as a mosaic when the checkerboard of the levels
(medians) of the four sites of its 2 x 2 cells (:func:`site_pattern`) exceeds this many times the
pixel noise."""

SITE_SAMPLE = 256
"""About this many 2 x 2 cells are sampled for :func:`site_levels`: the median of 256 noisy values
is within 0.08 noise sd of its site's level (one sd of the estimate), far below
:data:`MIN_CHECKERBOARD_SIGMA`; no grey frame of 300 (noise 0.3-20 counts) was taken for a
mosaic."""

HOT_SIGMA = 5.0
"""A mosaic's pixel is taken for hot (:func:`without_hot_sites`) from this many times the pixel
noise over its site's level ..."""

HOT_PEAK_FRACTION = 0.75
"""... when it holds more than this share of its 3 x 3 neighbourhood's light (the detector's own
default, :attr:`startrack.detect.DetectionSettings.max_peak_fraction`)."""

_COLOUR_LETTERS = "RGB"


def bayer_pattern(header: Mapping[str, Any]) -> str | None:
    """The colour of each site of the 2 x 2 cell at the array's first pixel, as four letters (row
    by row), from the header's ``BAYERPAT`` shifted by ``XBAYROFF`` / ``YBAYROFF``; None when the
    header names no pattern of :data:`BAYER_PATTERNS` (any case, blanks around it allowed)."""
    value = header.get("BAYERPAT")
    if not isinstance(value, str) or value.strip().upper() not in BAYER_PATTERNS:
        return None
    cells = np.array(list(value.strip().upper())).reshape(2, 2)
    dx, dy = (_offset(header.get(key)) for key in ("XBAYROFF", "YBAYROFF"))
    return "".join(np.roll(cells, (-dy, -dx), axis=(0, 1)).ravel())


def _offset(value: object) -> int:
    """A Bayer offset card's parity (0 or 1); 0 for a missing or non-integer value."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        return 0
    return int(value) % 2 if float(value).is_integer() else 0


def describe_mosaic(pattern: str) -> str:
    """How the commands and the web tool name a mosaic read at full resolution (``Image.mosaic``):
    "a colour-filter (Bayer) mosaic (pattern RGGB)", one found by its pixels alone, or a longer
    pattern ("a colour-filter mosaic (pattern GGRGGB/...)")."""
    if pattern == "unknown":
        return "a colour-filter (Bayer) mosaic (no BAYERPAT card; its sites' levels form a checkerboard)"
    kind = "colour-filter (Bayer) mosaic" if pattern in BAYER_PATTERNS else "colour-filter mosaic"
    return f"a {kind} (pattern {pattern})"


def site_pattern(data: NDArray) -> bool:
    """Whether the levels (medians, :func:`site_levels`) of the four sites of the 2 x 2 cells of
    ``data`` (H, W) form a checkerboard: half the difference of the sums of the two diagonals of the
    cell exceeds :data:`MIN_CHECKERBOARD_SIGMA` times the pixel noise and, for counts (integers,
    also in a float file), two counts, which the medians of whole counts can differ by. A linear
    gradient adds the same to both sums; a frame without noise (a rendering) is never taken."""
    if data.ndim != 2 or min(data.shape) < 4:
        return False
    levels, noise = site_levels(data)
    if not (np.isfinite(levels).all() and np.isfinite(noise)) or noise <= 0:
        return False
    checkerboard = 0.5 * abs(float(levels[0, 0] + levels[1, 1] - levels[0, 1] - levels[1, 0]))
    return checkerboard > max(MIN_CHECKERBOARD_SIGMA * noise, 2.0 * _count_step(levels, data))


def _count_step(levels: NDArray[np.float64], data: NDArray) -> float:
    """1.0 when ``data`` holds whole counts (an integer type, or a float one whose site levels and a
    sample of pixels are whole numbers), else 0.0 (a scaled float frame, e.g. 0 to 1)."""
    if data.dtype.kind in "iub":
        return 1.0
    sample = np.asarray(data[:: max(1, data.shape[0] // 64), :: max(1, data.shape[1] // 64)], dtype=np.float64)
    sample = sample[np.isfinite(sample)]
    whole = np.all(levels == np.round(levels)) and np.all(sample == np.round(sample))
    return 1.0 if whole else 0.0


def site_levels(data: NDArray) -> tuple[NDArray[np.float64], float]:
    """The median of each site of the 2 x 2 cells of ``data`` (H >= 2, W >= 4), shape (2, 2), and
    the pixel noise: the median absolute difference of neighbouring pixels of one site, scaled to a
    Gaussian's standard deviation (stars and gradients barely move either), NaN when there is none.
    Over a regular subsample of about :data:`SITE_SAMPLE` cells, whatever the frame's size: every
    FITS file read pays it (a 1024 x 1024 uint16 file, median of 300 reads: 0.95 ms against 0.68
    without; the call alone 0.14 ms)."""
    step = 2 * max(1, int(np.sqrt(data.size / 4 / SITE_SAMPLE)))
    rows = np.add.outer(np.arange(0, data.shape[0] - 1, step), (0, 1)).ravel()
    cols = np.add.outer(np.arange(0, data.shape[1] - 1, step), (0, 1)).ravel()
    cells = np.asarray(data[np.ix_(rows, cols)], dtype=np.float64).reshape(rows.size // 2, 2, cols.size // 2, 2)
    sites = cells.transpose(1, 3, 0, 2).reshape(4, -1)  # site (dy, dx) = row 2 dy + dx
    if np.isnan(sites).any():
        levels = np.array([float(np.median(site[np.isfinite(site)])) if np.isfinite(site).any() else np.nan
                           for site in sites])
    else:
        levels = np.median(sites, axis=1)
    steps = np.diff(cells, axis=2).ravel()
    steps = steps[np.isfinite(steps)]
    if steps.size == 0:
        return levels.reshape(2, 2), float("nan")
    return levels.reshape(2, 2), 1.4826 * float(np.median(np.abs(steps - np.median(steps)))) / np.sqrt(2.0)


def without_hot_sites(data: NDArray) -> NDArray[np.float32]:
    """A float32 copy of the mosaic ``data`` (H, W) whose hot pixels take the median of the four
    sites of their colour two pixels away. The kernel would spread a hot pixel into a star-sized
    blob that the detector's hot-pixel tests no longer tell from a star, so they are found first,
    as those tests find them: a pixel at least :data:`HOT_SIGMA` times the noise over its site's
    level that is the largest of its 3 x 3 neighbourhood and holds more than
    :data:`HOT_PEAK_FRACTION` of that neighbourhood's light. A Gaussian star centred on a pixel puts
    0.36 of that light in it at 0.6 px sd, 0.25 at 0.8 px; with the filters around passing little of
    its colour (green 0.3 and blue 0.1 of red's, for a red star on a red site) 0.70 and 0.59: such
    stars stay, sharper ones may go. Edges mirrored (:func:`mosaic_plane` does the same, strip by
    strip)."""
    plane = np.asarray(data, dtype=np.float32)
    if min(plane.shape) < 3:
        return plane.copy()
    levels, noise = site_levels(plane)
    return _cleaned(np.pad(plane, 2, mode="reflect"), (0, 0), levels, noise)


def _cleaned(block: NDArray[np.float32], origin: tuple[int, int], levels: NDArray[np.float64],
             noise: float) -> NDArray[np.float32]:
    """The region ``block[2:-2, 2:-2]`` (image pixel ``origin`` = (row, column) first) with its hot
    pixels replaced (:func:`without_hot_sites`); ``block`` holds two more pixels on every side."""
    h, w = block.shape[0] - 4, block.shape[1] - 4
    region = block[2:-2, 2:-2].copy()
    if not np.isfinite(noise) or noise <= 0 or not np.isfinite(levels).all():
        return region
    y0, x0 = origin
    hot = hot_sites(block[1:-1, 1:-1] - site_tile(levels.astype(np.float32), (y0 - 1, x0 - 1), (h + 2, w + 2)), noise)
    if hot.any():
        same = [block[2 + dy: 2 + dy + h, 2 + dx: 2 + dx + w][hot] for dy, dx in ((-2, 0), (2, 0), (0, -2), (0, 2))]
        region[hot] = np.median(np.stack(same), axis=0)
    return region


def hot_sites(excess: NDArray[np.float32], noise: float) -> NDArray[np.bool_]:
    """Which pixels of the inner (h, w) of ``excess`` (h + 2, w + 2: each pixel's value over its
    site's level) are hot (:func:`without_hot_sites`): at least :data:`HOT_SIGMA` times ``noise``
    over the level, the largest of their 3 x 3 neighbourhood, with more than
    :data:`HOT_PEAK_FRACTION` of its light."""
    h, w = excess.shape[0] - 2, excess.shape[1] - 2
    centre, peak, light = excess[1:-1, 1:-1], np.full((h, w), -np.inf, np.float32), excess[1:-1, 1:-1].copy()
    for dy, dx in ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)):
        neighbour = excess[1 + dy: 1 + dy + h, 1 + dx: 1 + dx + w]
        np.maximum(peak, neighbour, out=peak)
        light += neighbour
    with np.errstate(invalid="ignore"):
        return (centre > HOT_SIGMA * noise) & (centre >= peak) & (centre > HOT_PEAK_FRACTION * light)


def site_tile(cell: NDArray, origin: tuple[int, int], shape: tuple[int, int]) -> NDArray:
    """The 2 x 2 ``cell`` (one value per site, indexed by the image's row and column parity) laid
    over a region of ``shape`` whose first pixel is image pixel ``origin`` = (row, column)."""
    rolled = np.roll(cell, (-origin[0], -origin[1]), axis=(0, 1))
    return np.tile(rolled, ((shape[0] + 1) // 2, (shape[1] + 1) // 2))[:shape[0], :shape[1]]


def _kernel(block: NDArray[np.float32]) -> NDArray[np.float32]:
    """[1, 2, 1] x [1, 2, 1] / 16 over ``block`` (h + 2, w + 2): its inner (h, w) pixels."""
    rows = block[:-2] + 2.0 * block[1:-1] + block[2:]
    return (rows[:, :-2] + 2.0 * rows[:, 1:-1] + rows[:, 2:]) * np.float32(1 / 16)


def mosaic_luminance(data: NDArray) -> NDArray[np.float32]:
    """``data`` (H, W) correlated with [1, 2, 1] x [1, 2, 1] / 16 (module docstring), the edges
    mirrored about their outer pixels (which keeps each neighbour's colour): float32 (H, W), in
    the units of ``data``. NaN pixels spread to their eight neighbours."""
    plane = np.asarray(data, dtype=np.float32)
    return plane.copy() if min(plane.shape) < 2 else _kernel(np.pad(plane, 1, mode="reflect"))


def mosaic_channel(data: NDArray, pattern: str, channel: int) -> NDArray[np.float32]:
    """One colour (``channel`` 0 R, 1 G, 2 B) of the mosaic ``data`` (H, W) whose first cell is
    ``pattern`` (:func:`bayer_pattern`): that colour's sites as they are, the others interpolated
    bilinearly from them (module docstring). float32 (H, W)."""
    mask = _colour_mask(pattern, channel)
    plane = np.asarray(data, dtype=np.float32)
    return mosaic_luminance(plane * site_tile(mask, (0, 0), plane.shape)) / np.float32(mask.mean())


def _colour_mask(pattern: str, channel: int) -> NDArray[np.float32]:
    """1 on the sites of colour ``channel`` (0 R, 1 G, 2 B) of the 2 x 2 ``pattern``, else 0."""
    return np.array([site == _COLOUR_LETTERS[channel] for site in pattern], dtype=np.float32).reshape(2, 2)


STRIP_ROWS = 256
""":func:`mosaic_plane` works on strips of this many rows, so that a large frame's temporaries stay
a few strips' worth: a 6248 x 4176 uint16 frame (52 MB) peaked at 251 MB (tracemalloc), against
1,280 MB when each step took the whole frame."""


def mosaic_plane(data: NDArray, pattern: str | None = None, channel: int | None = None) -> NDArray[np.float32]:
    """The full-resolution plane of the mosaic ``data`` (H, W): hot sites replaced
    (:func:`without_hot_sites`), then the luminance (:func:`mosaic_luminance`) or, with a
    ``pattern`` and a ``channel``, that colour (:func:`mosaic_channel`); strip by strip of
    :data:`STRIP_ROWS`, the same values as those functions give in turn. float32 (H, W)."""
    if min(data.shape) < 3:
        return mosaic_luminance(data) if channel is None or pattern is None else mosaic_channel(data, pattern, channel)
    levels, noise = site_levels(data)
    mask = None if channel is None or pattern is None else _colour_mask(pattern, channel)
    # 2 more pixels for the hot pixels' neighbours, 1 for the kernel; padded in the file's type
    padded = np.pad(data, 3, mode="reflect").astype(np.float32, copy=False)
    out = np.empty(data.shape, np.float32)
    for r0 in range(0, data.shape[0], STRIP_ROWS):
        r1 = min(data.shape[0], r0 + STRIP_ROWS)
        cleaned = _cleaned(padded[r0: r1 + 6], (r0 - 1, -1), levels, noise)  # image rows r0 - 1 to r1
        if mask is not None:
            cleaned *= site_tile(mask, (r0 - 1, -1), cleaned.shape)
        out[r0:r1] = _kernel(cleaned)
    if mask is not None:
        out /= np.float32(mask.mean())
    return out


def from_mosaic(data: NDArray, header: Mapping[str, Any], channel: int | None) -> tuple[NDArray, str | None]:
    """A FITS image plane as startrack reads it: the full-resolution plane of a Bayer mosaic
    (:func:`mosaic_plane`: the luminance, or one colour for a ``channel``), and the pattern (the
    header's, or "unknown" when :func:`site_pattern` found it in the pixels); ``data`` itself and
    None for any other plane (a colour cube, a grey sensor's frame).

    Raises
    ------
    InvalidInputError
        If a ``channel`` is asked of a mosaic whose header does not name its pattern.
    """
    if data.ndim != 2:
        return data, None
    pattern = bayer_pattern(header)
    if pattern is None:
        if not site_pattern(data):
            return data, None
        if channel is not None:
            raise InvalidInputError("the image is a colour-filter mosaic whose header names no pattern (BAYERPAT): "
                                    "no colour can be picked from it; leave the channel out to use all sites")
        return mosaic_plane(data), "unknown"
    return mosaic_plane(data, pattern, channel), pattern
