"""Colour-filter arrays of any period (Fujifilm's 6 x 6 X-Trans, ...), read at full resolution.

:mod:`startrack.io._mosaic` reads the 2 x 2 Bayer mosaics through one fixed kernel. A filter
array with a longer period has no such kernel: around one site the 3 x 3 neighbourhood may hold
five greens, two reds and two blues, around the next three greens, four reds and two blues. Each
site therefore gets its own weights (:func:`phase_weights`): within its 3 x 3 neighbourhood, each
colour's sites share that colour's part of :data:`NEUTRAL_MIX` in proportion to the
[1, 2, 1] x [1, 2, 1] kernel. Every output pixel is then the same colour mix (R, G, B in the
proportions 1 : 2 : 1 of a Bayer cell), and a star's light is weighed the same wherever it falls.
On a 2 x 2 Bayer pattern the weights are exactly those of the kernel of :mod:`._mosaic`. One
colour (``channel``) is that colour's sites weighted alone: a normalised convolution.

The frame is padded by copying, for each row (column) outside it, the nearest row (column) inside
it of the same phase of the pattern, so that the pattern continues unbroken to the edges (for a
period of 2 this is the mirror padding of :mod:`._mosaic`).

Hot pixels are replaced first, by the test of :func:`._mosaic.hot_sites` against each colour's
level, with the median of the sites of their colour within two pixels.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ._channels import channel_index
from ._mosaic import BAYER_PATTERNS, STRIP_ROWS, hot_sites, mosaic_plane

NEUTRAL_MIX = np.array([0.25, 0.5, 0.25])
"""The share of red, green and blue in every output pixel of a luminance (the share of each colour
in a Bayer cell, and so the same mix as :mod:`._mosaic` gives)."""

LEVEL_BLOCKS = 48
"""The colours' levels and the noise (:func:`colour_levels`) are measured on about this many blocks
of rows by as many of columns."""

_KERNEL = np.outer([1.0, 2.0, 1.0], [1.0, 2.0, 1.0]) / 16.0
_COLOURS = 3


def phase_weights(colours: NDArray[np.integer], mix: NDArray[np.floating]) -> NDArray[np.float32]:
    """The 3 x 3 weights of each site of the pattern.

    Parameters
    ----------
    colours : ndarray of int, shape (P, Q)
        The colour (0 R, 1 G, 2 B) of each site of one period of the pattern, from the array's
        first pixel.
    mix : ndarray, shape (3,)
        Each colour's share of the output (:data:`NEUTRAL_MIX`, or one colour's 1 for a channel).

    Returns
    -------
    ndarray, float32, shape (P, Q, 3, 3)
        ``[i, j, 1 + dy, 1 + dx]`` weighs the pixel (dy, dx) from a site of phase (i, j).

    Raises
    ------
    InvalidInputError
        If some site's 3 x 3 neighbourhood lacks a colour that ``mix`` asks for.
    """
    p, q = colours.shape
    rows = (np.arange(p)[:, None] + np.arange(-1, 2)[None, :]) % p  # (P, 3)
    cols = (np.arange(q)[:, None] + np.arange(-1, 2)[None, :]) % q  # (Q, 3)
    around = colours[rows[:, None, :, None], cols[None, :, None, :]]  # (P, Q, 3, 3)
    weights = np.zeros(around.shape)
    for colour in np.flatnonzero(mix):
        share = np.where(around == colour, _KERNEL, 0.0)
        total = share.sum(axis=(2, 3), keepdims=True)
        if not (total > 0).all():
            raise InvalidInputError(f"the colour-filter pattern leaves {'RGB'[colour]} out of the 3 x 3 "
                                    "neighbourhood of some of its sites: it cannot be evened out")
        weights += mix[colour] * share / total
    return weights.astype(np.float32)


def phase_indices(n: int, pad: int, period: int) -> NDArray[np.intp]:
    """Indices of the ``n + 2 pad`` rows (or columns) of a frame padded by ``pad``: inside, their
    own; outside, the nearest inside of the same phase modulo ``period`` (clipped to the frame
    when it is shorter than that)."""
    index = np.arange(-pad, n + pad)
    low = index < 0
    index[low] += period * -(index[low] // period)
    high = index >= n
    index[high] -= period * ((index[high] - n) // period + 1)
    return np.clip(index, 0, n - 1)


def phase_padded(data: NDArray, pad: int, period: tuple[int, int]) -> NDArray[np.float32]:
    """``data`` (H, W) as float32, padded by ``pad`` on every side with :func:`phase_indices`."""
    rows = phase_indices(data.shape[0], pad, period[0])
    cols = phase_indices(data.shape[1], pad, period[1])
    return np.asarray(data, dtype=np.float32)[np.ix_(rows, cols)]


def colour_levels(data: NDArray, colours: NDArray[np.integer]) -> tuple[NDArray[np.float64], float]:
    """The median of each colour's sites (shape (3,), NaN for a colour the pattern lacks) and the
    pixel noise: the median absolute difference of sites one period apart along a row, scaled to
    a Gaussian's standard deviation (NaN when there is none). Over about :data:`LEVEL_BLOCKS` x
    :data:`LEVEL_BLOCKS` blocks of a period of rows by two of columns, whatever the frame's size."""
    p, q = colours.shape
    rows = _blocks(data.shape[0], p)
    cols = _blocks(data.shape[1], 2 * q)
    sample = np.asarray(data[np.ix_(rows, cols)], dtype=np.float64)
    colour = colours[(rows % p)[:, None], (cols % q)[None, :]]
    levels = np.full(_COLOURS, np.nan)
    for c in range(_COLOURS):
        values = sample[(colour == c) & np.isfinite(sample)]
        if values.size:
            levels[c] = float(np.median(values))
    if cols.size % (2 * q):  # narrower than two periods: no pair of sites a period apart
        return levels, float("nan")
    steps = np.diff(sample.reshape(rows.size, -1, 2, q), axis=2).ravel()
    steps = steps[np.isfinite(steps)]
    if steps.size == 0:
        return levels, float("nan")
    return levels, 1.4826 * float(np.median(np.abs(steps - np.median(steps)))) / np.sqrt(2.0)


def _blocks(n: int, size: int) -> NDArray[np.intp]:
    """Indices of about :data:`LEVEL_BLOCKS` evenly spaced runs of ``size`` consecutive indices
    below ``n``, each starting at a multiple of ``size`` (all of them when ``n`` is short)."""
    if n < size:
        return np.arange(n)
    step = size * max(1, n // size // LEVEL_BLOCKS)
    return (np.arange(0, n - size + 1, step)[:, None] + np.arange(size)).ravel()


def pattern_tile(cell: NDArray, origin: tuple[int, int], shape: tuple[int, int]) -> NDArray:
    """The periodic ``cell`` (P, Q: one value per site of the pattern, from the image's first pixel)
    laid over a region of ``shape`` whose first pixel is image pixel ``origin`` = (row, column)."""
    p, q = cell.shape
    rows = (origin[0] + np.arange(shape[0])) % p
    cols = (origin[1] + np.arange(shape[1])) % q
    return cell[rows[:, None], cols[None, :]]


def cleaned_block(block: NDArray[np.float32], origin: tuple[int, int], colours: NDArray[np.integer],
                  levels: NDArray[np.float64], noise: float) -> NDArray[np.float32]:
    """The region ``block[2:-2, 2:-2]`` (image pixel ``origin`` = (row, column) first; ``block``
    phase-padded by two more pixels on every side) with its hot pixels (:func:`._mosaic.hot_sites`
    over each colour's level) replaced by the median of the other sites of their colour in their
    5 x 5 neighbourhood."""
    h, w = block.shape[0] - 4, block.shape[1] - 4
    region = block[2:-2, 2:-2].copy()
    if not np.isfinite(noise) or noise <= 0 or not np.isfinite(levels[np.unique(colours)]).all():
        return region
    inner = (origin[0] - 1, origin[1] - 1)
    level = np.nan_to_num(levels).astype(np.float32)[pattern_tile(colours, inner, (h + 2, w + 2))]
    hot = hot_sites(block[1:-1, 1:-1] - level, noise)
    if hot.any():
        region[hot] = _same_colour_median(block, origin, colours, np.nonzero(hot), levels)
    return region


def _same_colour_median(block: NDArray[np.float32], origin: tuple[int, int], colours: NDArray[np.integer],
                        where: tuple[NDArray[np.intp], ...], levels: NDArray[np.float64]) -> NDArray[np.float32]:
    """For the pixels ``where`` (rows, columns of ``block[2:-2, 2:-2]``), the median of the other
    finite pixels of their colour in their 5 x 5 neighbourhood in ``block``; their colour's level
    (``levels``, shape (3,)) where there is none."""
    p, q = colours.shape
    ys, xs = where
    offsets = [(dy, dx) for dy in range(-2, 3) for dx in range(-2, 3) if dy or dx]
    own = colours[(origin[0] + ys) % p, (origin[1] + xs) % q]
    values = np.full((ys.size, len(offsets)), np.nan, np.float32)
    for k, (dy, dx) in enumerate(offsets):
        same = colours[(origin[0] + ys + dy) % p, (origin[1] + xs + dx) % q] == own
        values[same, k] = block[2 + ys[same] + dy, 2 + xs[same] + dx]
    out = levels[own].astype(np.float32)
    found = np.isfinite(values).any(axis=1)
    out[found] = np.nanmedian(values[found], axis=1)
    return out


def _correlated(block: NDArray[np.float32], origin: tuple[int, int], weights: NDArray[np.float32]
                ) -> NDArray[np.float32]:
    """The inner (h, w) pixels of ``block`` (h + 2, w + 2), each the sum of its 3 x 3
    neighbourhood under the :func:`phase_weights` of its site (image pixel ``origin`` first)."""
    p, q = weights.shape[:2]
    h, w = block.shape[0] - 2, block.shape[1] - 2
    out = np.zeros((h, w), np.float32)
    for i in range(min(p, h)):
        for j in range(min(q, w)):
            phase = weights[(origin[0] + i) % p, (origin[1] + j) % q]
            ny, nx = len(range(i, h, p)), len(range(j, w, q))
            target = out[i::p, j::q]
            for dy in range(3):
                for dx in range(3):
                    r0, c0 = i + dy, j + dx
                    target += phase[dy, dx] * block[r0: r0 + (ny - 1) * p + 1: p, c0: c0 + (nx - 1) * q + 1: q]
    return out


def cfa_plane(data: NDArray, colours: NDArray[np.integer], channel: int | None = None) -> NDArray[np.float32]:
    """The full-resolution plane of the colour-filter mosaic ``data`` (H, W) whose pattern, from
    its first pixel, is ``colours`` (P, Q) of 0 R, 1 G, 2 B: hot sites replaced, then every pixel
    the same colour mix (:data:`NEUTRAL_MIX`) or, with ``channel`` (0, 1, 2), that colour alone
    (module docstring). Strip by strip of :data:`._mosaic.STRIP_ROWS`. float32 (H, W), the units
    of ``data``.

    Raises
    ------
    InvalidInputError
        If the pattern leaves a colour out of some site's 3 x 3 neighbourhood.
    """
    colours = np.asarray(colours, dtype=np.intp)
    mix = NEUTRAL_MIX if channel is None else np.eye(_COLOURS)[channel]
    weights = phase_weights(colours, mix)
    levels, noise = colour_levels(data, colours)
    padded = phase_padded(data, 3, colours.shape)  # 2 pixels for the hot pixels' neighbours, 1 for the kernel
    out = np.empty(data.shape, np.float32)
    for r0 in range(0, data.shape[0], STRIP_ROWS):
        r1 = min(data.shape[0], r0 + STRIP_ROWS)
        cleaned = cleaned_block(padded[r0: r1 + 6], (r0 - 1, -1), colours, levels, noise)  # image rows r0 - 1 to r1
        out[r0:r1] = _correlated(cleaned, (r0, 0), weights)
    return out


def mosaic_to_plane(data: ArrayLike, pattern: str, channel: str | int | None = None) -> NDArray[np.float32]:
    """The full-resolution plane of a raw colour-filter mosaic, as :func:`startrack.io.read_image`
    reads one from a FITS or camera RAW file: for an array a camera's own software gave.

    Parameters
    ----------
    data : array_like, shape (H, W)
        The photosites' counts (above the bias or black level, if the colours are to be right).
    pattern : str
        The filters from the array's first pixel, row by row: four letters for a 2 x 2 Bayer
        pattern ("RGGB", "BGGR", "GRBG", "GBRG"), or the rows of a longer one joined by "/" (an
        X-Trans sensor's "GGRGGB/GGBGGR/BRGRBG/GGBGGR/GGRGGB/RBGBRG"); any case.
    channel : {None, "r", "g", "b", 0, 1, 2}
        None for the colour-neutral luminance, else that colour's sites interpolated.

    Returns
    -------
    ndarray, float32, shape (H, W)
        Hot sites replaced, in the units of ``data`` (:mod:`._mosaic`, :mod:`._cfa`).

    Raises
    ------
    InvalidInputError
        For a pattern of other letters than R, G, B, rows of unequal length, a pattern missing a
        colour or leaving one out of some site's 3 x 3 neighbourhood, or an array that is not 2-D.
    """
    array = np.asarray(data)
    if array.ndim != 2:
        raise InvalidInputError(f"a mosaic must be a 2-D array of photosites, got shape {array.shape}")
    colours = pattern_colours(pattern)
    index = channel_index(channel)
    text = "".join("RGB"[c] for c in colours.ravel())
    if colours.shape == (2, 2) and text in BAYER_PATTERNS:
        return mosaic_plane(array, text, index)
    return cfa_plane(array, colours, index)


def pattern_colours(pattern: str) -> NDArray[np.intp]:
    """The colours (0 R, 1 G, 2 B), shape (P, Q), of a pattern written as :func:`mosaic_to_plane`
    takes it; InvalidInputError for anything else."""
    text = str(pattern).strip().upper()
    rows = text.split("/") if "/" in text else [text[:2], text[2:]] if len(text) == 4 else [text]
    valid = len({len(row) for row in rows}) == 1 and set("".join(rows)) == set("RGB")
    if not valid:
        raise InvalidInputError(f"a mosaic pattern must be four letters of R, G and B (e.g. 'RGGB') or equal rows "
                                f"of them joined by '/' (e.g. an X-Trans 'GGRGGB/GGBGGR/...'), got {pattern!r}")
    return np.array([["RGB".index(c) for c in row] for row in rows], dtype=np.intp)
