"""Where the tiled background model samples an image, and how its tile grids are interpolated.

A tile grid holds one value per tile at the tile centres; the values between them (at pixels,
at sample positions, at points) are bilinear interpolations along each axis, extended linearly
or held constant beyond the outer centres (:func:`axis_weights`). The positions an image of a
given shape is sampled at, and their interpolation weights, are the same for every frame of a
camera, so they are computed once and cached (:func:`tile_layout`, :func:`strided_weights`);
the cached arrays are shared between calls and must not be written to (the compiled loops take
writeable arrays, so they are not flagged read-only).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._compiled import kernels

TILE_SAMPLES = 256
"""Pixels per tile used for the tile statistics (a strided subsample)."""


def spacing(centres: NDArray) -> float:
    """The spacing of equally spaced ``centres`` (1 for a single centre, where it is not used)."""
    return float(centres[1] - centres[0]) if centres.size > 1 else 1.0


def axis_weights(centres: NDArray, coords: NDArray, extrapolate: bool
                 ) -> tuple[NDArray, NDArray, NDArray]:
    """Lower index, upper index and upper weight of linear interpolation along one axis.

    ``centres`` are equally spaced. Beyond the outer centres (the outer half tile) the value
    is held constant, or, with ``extrapolate``, the line through the two outer centres is
    extended (the weight clipped to [-0.75, 1.75]) so that a gradient is followed to the edge.
    """
    n = centres.size
    if n == 1:
        zero = np.zeros(coords.shape, dtype=np.int64)
        return zero, zero, np.zeros(coords.shape)
    pos = (coords - centres[0]) / (centres[1] - centres[0])
    i0 = np.minimum(np.maximum(np.floor(pos).astype(np.int64), 0), n - 2)
    low, high = (-0.75, 1.75) if extrapolate else (0.0, 1.0)
    return i0, i0 + 1, np.minimum(np.maximum(pos - i0, low), high)


def grid_map(grid: NDArray, centres_y: NDArray, centres_x: NDArray, ys: NDArray, xs: NDArray,
             extrapolate: bool) -> NDArray[np.float32]:
    """Bilinear interpolation of ``grid`` (values at centres_y x centres_x) on the grid of rows
    ``ys`` x columns ``xs`` (beyond the outer centres: see :func:`axis_weights`); float32
    array of shape (len(ys), len(xs)), along x first (:func:`.frame_kernels.grid_map`)."""
    y0, y1, wy = axis_weights32(centres_y, np.asarray(ys, dtype=float), extrapolate)
    x0, x1, wx = axis_weights32(centres_x, np.asarray(xs, dtype=float), extrapolate)
    return kernels().grid_map(grid.astype(np.float32), y0, y1, wy, x0, x1, wx)


def axis_weights32(centres: NDArray, coords: NDArray, extrapolate: bool = True) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`axis_weights` with the weights as float32, as the compiled loops take them."""
    i0, i1, weight = axis_weights(centres, coords, extrapolate)
    return i0, i1, weight.astype(np.float32)


def strided_map(grid: NDArray, centres_y: NDArray, centres_x: NDArray, shape: tuple[int, int],
                step: int) -> NDArray[np.float32]:
    """:func:`grid_map` of ``grid`` (extrapolated) on the rows and columns ``step * arange(n)``
    of a strided sample of ``shape`` (n_rows, n_cols), the axis weights cached
    (:func:`strided_weights`: the same for every frame of a camera)."""
    y0, y1, wy = strided_weights(centres_y, shape[0], step)
    x0, x1, wx = strided_weights(centres_x, shape[1], step)
    return kernels().grid_map(grid.astype(np.float32), y0, y1, wy, x0, x1, wx)


def strided_weights(centres: NDArray, n: int, step: int, offset: float = 0.0) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`axis_weights` (extrapolated) of the coordinates ``offset + step * arange(n)``
    between ``centres``, the weights float32; cached (module docstring)."""
    return _strided_weights(tuple(centres.tolist()), n, step, offset)


@functools.lru_cache(maxsize=32)
def _strided_weights(centres: tuple[float, ...], n: int, step: int, offset: float) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`strided_weights` of hashable arguments."""
    return axis_weights32(np.array(centres), offset + step * np.arange(n, dtype=float))


def tile_rows_cols(shape: tuple[int, int], tile: int) -> tuple[NDArray, NDArray]:
    """The rows and columns of a regular subsample of every tile, about :data:`TILE_SAMPLES`
    pixels each, tile after tile: shapes (ny * n_rows,), (nx * n_cols,) of int64.

    The grid has max(1, H // tile) x max(1, W // tile) equal tiles; the last H % tile rows and
    W % tile columns are left out.
    """
    h, w = shape
    ny, nx = max(1, h // tile), max(1, w // tile)
    tile_h, tile_w = h // ny, w // nx
    step = max(1, int(np.sqrt(tile_h * tile_w / TILE_SAMPLES)))
    rows = (np.arange(ny)[:, None] * tile_h + np.arange(0, tile_h, step)).ravel()
    cols = (np.arange(nx)[:, None] * tile_w + np.arange(0, tile_w, step)).ravel()
    return rows, cols


AxisWeights = tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]
"""Rows' and columns' interpolation weights (y0, y1, wy, x0, x1, wx), the weights float32
(:func:`residual_weights`)."""


@dataclass(frozen=True)
class TileLayout:
    """Where a tiled model of an image of one shape samples it (:func:`tile_rows_cols`): the
    sampled rows and columns, the tile grid (ny, nx), the tile centres (the mean sampled row and
    column of each tile) and the samples' interpolation weights between them; cached by
    :func:`tile_layout` (module docstring)."""

    rows: NDArray
    cols: NDArray
    grid: tuple[int, int]
    centres_y: NDArray
    centres_x: NDArray
    weights: AxisWeights


@functools.lru_cache(maxsize=16)
def tile_layout(shape: tuple[int, int], tile: int) -> TileLayout:
    """The :class:`TileLayout` of ``tile`` x ``tile`` tiles on an image of ``shape`` (the same
    for every frame of a camera, so computed once)."""
    rows, cols = tile_rows_cols(shape, tile)
    ny, nx = max(1, shape[0] // tile), max(1, shape[1] // tile)
    centres_y, centres_x = rows.reshape(ny, -1).mean(axis=1), cols.reshape(nx, -1).mean(axis=1)
    return TileLayout(rows, cols, (ny, nx), centres_y, centres_x, residual_weights(centres_y, centres_x, rows, cols))


def residual_weights(centres_y: NDArray, centres_x: NDArray, rows: NDArray, cols: NDArray) -> AxisWeights:
    """The interpolation weights (extrapolated beyond the outer centres, :func:`axis_weights`)
    of the sampled ``rows`` and ``cols`` between tile centres, weights as float32."""
    return (*axis_weights32(centres_y, rows.astype(float)), *axis_weights32(centres_x, cols.astype(float)))
