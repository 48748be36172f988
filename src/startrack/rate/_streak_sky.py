"""The sky under a frame's streaks, block by block, for the streak search (:mod:`._streak_find`).

One level for the whole frame (its median) leaves the sky's own slopes in the line-filtered image:
the glow of the Earth's limb or the Moon on a star tracker's frame, light pollution, vignetting
and lit foreground on a photograph. There they raise the threshold's robust sigma and pass it in
wide patches, while the streaks elsewhere stay under it (a trailed photograph under a sky
gradient gave no candidate at all). Here the level is the median of each tile of
:data:`SKY_TILE_BLOCKS` x :data:`SKY_TILE_BLOCKS` blocks, interpolated bilinearly between the
tiles' centres and extrapolated beyond the outer ones (half tiles along the edges:
:func:`edged_levels`), then taken again with the blocks :data:`CLIP_NOISES` block noises above it
set to it. A streak covers a few of a tile's 64 blocks, which the median passes over. A frame
whose level spans less than :data:`FLAT_SPAN_NOISES` block noises over larger tiles keeps the one
level (:func:`sloped_sky`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

SKY_TILE_BLOCKS = 8
"""Side of the tiles of the sky level, in blocks (32 px at the search's 4 px blocks). Tiles of 64 px
left the glow of a limb (200 e- at the edge, falling by e over 150 px) standing along the frame's
edge, where the extrapolation of the last two tiles' levels falls short of its curve, and the
search took that strip for a 1000 px streak."""
GATE_TILE_BLOCKS = 16
"""Side of the tiles, in blocks, whose levels tell a sloping sky from a flat one (:func:`sloped_sky`):
twice :data:`SKY_TILE_BLOCKS`, so that their medians carry half the noise."""
FLAT_SPAN_NOISES = 2.0
"""The span of the medians of :data:`GATE_TILE_BLOCKS` tiles, in block noises (the frame's pixel
noise times the block side), under which the sky is flat. Measured: simulated generic-cmos frames
of a 12 deg field, smeared, with or without 200 e- of flat stray light, span 0.40-0.59 (the noise
of 256 medians of 256 blocks: 0.08 block noises each); the same frames under a ramp of 50 or
200 e- across span 9.8-10.2, and the eight real photographs of ../shared/realdata, trailed over
20 px, 4.4-30."""
CLIP_NOISES = 2.0
"""Blocks this many block noises above the first level are set to it before the level is taken
again: the light of streaks and stars, which would raise their tiles' medians."""


def sloped_sky(blocks: NDArray, block_noise: float) -> NDArray[np.float64] | None:
    """:func:`block_sky` when the levels of :data:`GATE_TILE_BLOCKS` tiles span more than
    :data:`FLAT_SPAN_NOISES` times ``block_noise`` (counts per block); None for a flat sky, which
    the frame's one level serves as well."""
    if float(np.ptp(tile_levels(blocks, GATE_TILE_BLOCKS))) <= FLAT_SPAN_NOISES * block_noise:
        return None
    first = block_sky(blocks)
    return block_sky(np.where(blocks - first > CLIP_NOISES * block_noise, first, blocks))


def block_sky(blocks: NDArray, tile: int = SKY_TILE_BLOCKS) -> NDArray[np.float64]:
    """The sky level of each block of a binned frame (module docstring).

    Parameters
    ----------
    blocks : ndarray, shape (NY, NX)
        The frame's block sums (counts per block); at least ``tile`` blocks a side.
    tile : int
        Tile side in blocks (even).

    Returns
    -------
    ndarray, shape (NY, NX)
        The sky level of each block (counts per block).
    """
    return _interpolated(*edged_levels(blocks, tile), blocks.shape)


def _interpolated(level: NDArray, cy: NDArray, cx: NDArray, shape: tuple[int, int]) -> NDArray[np.float64]:
    """Tile values ``level`` (KY, KX) at centres ``cy``, ``cx`` (blocks) interpolated bilinearly
    to every block of a frame of ``shape`` blocks (extrapolated past the outer centres)."""
    ly, hy, wy = _between(shape[0], cy)
    lx, hx, wx = _between(shape[1], cx)
    wy, wx = wy[:, None], wx[None, :]
    return ((1 - wy) * ((1 - wx) * level[ly][:, lx] + wx * level[ly][:, hx])
            + wy * ((1 - wx) * level[hy][:, lx] + wx * level[hy][:, hx]))


def tile_levels(blocks: NDArray, tile: int) -> NDArray[np.float64]:
    """The median of each whole tile of ``tile`` x ``tile`` blocks (fewer when the frame is
    smaller), shape (NY // tile, NX // tile); the blocks past the last whole tile are left out."""
    ny, nx = blocks.shape
    t = max(1, min(tile, ny, nx))
    return _medians(blocks[: ny // t * t, : nx // t * t], t, t)


def edged_levels(blocks: NDArray, tile: int) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Tile medians whose outermost row and column are half a tile deep, and their centres.

    Along each axis: a strip of ``tile // 2`` blocks at each edge, and whole tiles between them
    (the few blocks past the last whole one are left out). The outermost levels then lie a
    quarter tile from the edge, and are extrapolated over that quarter: extrapolating whole tiles
    over half a tile fell short of a limb's glow, whose curve left a strip of light along the
    edge that the search took for a 1000 px streak.

    Returns
    -------
    level : ndarray, shape (KY + 2, KX + 2)
    cy, cx : ndarray, shapes (KY + 2,) and (KX + 2,)
        The tiles' centres, in blocks.
    """
    (ny, nx), h = blocks.shape, tile // 2
    (ry, ky), (rx, kx) = _spans(ny, tile), _spans(nx, tile)
    rows = [(slice(0, h), h), (slice(h, h + ky * tile), tile), (slice(ny - h, ny), h)]
    cols = [(slice(0, h), h), (slice(h, h + kx * tile), tile), (slice(nx - h, nx), h)]
    level = np.block([[_medians(blocks[r, c], a, b) for c, b in cols] for r, a in rows])
    return level, ry, rx


def _spans(n: int, tile: int) -> tuple[NDArray[np.float64], int]:
    """The centres (blocks) of an axis's edge strips and whole tiles (:func:`edged_levels`), and
    how many whole tiles there are."""
    h = tile // 2
    k = (n - 2 * h) // tile
    inner = h + tile * np.arange(k) + 0.5 * (tile - 1)
    return np.concatenate([[0.5 * (h - 1)], inner, [n - h + 0.5 * (h - 1)]]), k


def _medians(region: NDArray, a: int, b: int) -> NDArray[np.float64]:
    """Medians of the ``a`` x ``b`` tiles of ``region`` (its sides multiples of them), shape
    (rows // a, cols // b)."""
    ry, rx = region.shape[0] // a, region.shape[1] // b
    tiles = np.asarray(region, dtype=np.float64).reshape(ry, a, rx, b).swapaxes(1, 2)
    return np.median(tiles.reshape(ry, rx, a * b), axis=-1)


def _between(n: int, centres: NDArray) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
    """For each of ``n`` blocks along an axis: the tiles whose ``centres`` (ascending) bound it
    (lower, upper) and the weight of the upper one, extrapolated past the outer centres (a weight
    below 0 or above 1: held there, the last quarter tile of a limb's glow stood above it)."""
    at = np.arange(n, dtype=np.float64)
    low = np.clip(np.searchsorted(centres, at, side="right") - 1, 0, centres.size - 2)
    return low, low + 1, (at - centres[low]) / (centres[low + 1] - centres[low])
