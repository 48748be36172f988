"""Background level and noise of an image, global or on a coarse grid of tiles.

Huffman 2006 §4.1 subtracts a dark frame and thresholds at k times the
noise; a single image has no dark frame, so the level and the noise are estimated from the
image itself with the robust statistics of :mod:`._robust`.

The tiled model (SExtractor-like) takes the median and noise of each tile, median-filters the
tile grid (3 x 3) so that a bright star or a small cluster cannot pull one tile, and
interpolates bilinearly between tile centres. Busy regions (trees, roofs, clouds) get a high
local noise, hence a high threshold; the global noise is the lower quartile of the tile
noises, i.e. that of the clean sky. A frame whose noise is clipped at zero, and so skewed
upwards, gets its noise scaled to the width of the upper half (:func:`upper_tail_factor`),
the side a threshold cuts. A third grid, the *clutter* ratio, compares each tile's
lower-half width (median - 15.87 % quantile, which stars cannot raise) with the clean sky's:
about 1 on sky with or without stars, several times more on lit leaves or roof texture. It is
measured twice, on the tile's raw values and, as the noise is, on their residual from the
interpolated level, and the smaller of the two ratios counts (:func:`clutter_ratios`), so that
the Moon's glow, whose gradient widens a tile's raw values, is not taken for clutter.
Where the tiles sample the image and how their grids are interpolated is
:mod:`._tile_geometry`'s.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ._compiled import kernels
from ._robust import GAUSS_HI, GAUSS_LO, clipped_level_noise, quantization_step, strided_sample
from ._tile_geometry import AxisWeights, grid_map, spacing, strided_map, tile_layout, tile_rows_cols
from ._windows import fast_median, fast_quantile

CLEAN_SKY_QUANTILE = 0.25
"""The global noise of a tiled model is this quantile of the tile noises: the clean sky even
when trees or a roof fill more than half of the frame."""

CLIPPED_FRACTION = 0.05
"""A frame with this fraction of its pixels at its minimum has a clipped low side."""

MIN_NOISE_RATIO = 0.7
"""No tile's noise is taken below this fraction of the clean sky's (guards flat or quantized
tiles against a zero noise; :func:`tile_noise_floor`)."""


@dataclass(frozen=True)
class TileGrid:
    """The per-tile grids of a tiled background model, all set together.

    Attributes
    ----------
    level, noise : ndarray, shape (ny, nx)
        Per-tile level and noise (standard deviation), in the image's units.
    clutter : ndarray, shape (ny, nx)
        Per-tile clutter ratio (module docstring).
    centres_y, centres_x : ndarray, shape (ny,), (nx,)
        Tile-centre coordinates, in the pixel convention of the image they are evaluated on.
    clutter_reference : float
        The clean sky's lower-half width that the clutter ratios are relative to, image units
        (NaN when not known).
    """

    level: NDArray[np.float64]
    noise: NDArray[np.float64]
    clutter: NDArray[np.float64]
    centres_y: NDArray[np.float64]
    centres_x: NDArray[np.float64]
    clutter_reference: float = float("nan")

    def map(self, grid: NDArray, ys: NDArray, xs: NDArray, extrapolate: bool) -> NDArray[np.float32]:
        """``grid`` (one of these grids) on the grid of rows ``ys`` x columns ``xs``
        (:func:`.tile_geometry.grid_map`)."""
        return grid_map(grid, self.centres_y, self.centres_x, ys, xs, extrapolate)

    def at_points(self, x: NDArray, y: NDArray, which: slice) -> NDArray[np.float64]:
        """The grids ``(level, noise, clutter)[which]`` at the points (x, y) (arrays of one shape),
        bilinearly interpolated (the level extended linearly beyond the outer centres, the others
        held, :func:`.tile_geometry.axis_weights`): float64 (K, *x.shape). One compiled loop
        (:func:`.frame_kernels.grid_at_points`)."""
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        grids, extrapolate, first, steps = self._stacked  # not `spacing`: the function of that name
        out = kernels().grid_at_points(grids[which], extrapolate[which], first, steps, y.ravel(), x.ravel())
        return out.reshape((out.shape[0], *x.shape))

    @functools.cached_property
    def _stacked(self) -> tuple[NDArray, NDArray, NDArray, NDArray]:
        """The three grids as one float64 array (3, ny, nx), which of them are extrapolated, and
        the first tile centre and the centre spacing (rows, columns), px."""
        grids = np.ascontiguousarray(np.stack([self.level, self.noise, self.clutter]), dtype=np.float64)
        first = np.array([self.centres_y[0], self.centres_x[0]], dtype=np.float64)
        steps = np.array([spacing(self.centres_y), spacing(self.centres_x)])
        return grids, np.array([True, False, False]), first, steps


@dataclass(frozen=True)
class BackgroundModel:
    """Background level and noise of an image, constant or on a grid of tile centres.

    Attributes
    ----------
    level, noise : float
        Global background level and noise (standard deviation), in the image's units.
    tiles : TileGrid or None
        The per-tile level, noise and clutter grids and the tile centres; None for a constant
        model.
    level_map : ndarray of float32, shape of the measured image, or None
        The interpolated level at every pixel of the image the model was measured on, when it
        was computed anyway (tiles covering the whole image); saves the thresholding one
        interpolation.
    """

    level: float
    noise: float
    tiles: TileGrid | None = None
    level_map: NDArray[np.float32] | None = field(default=None, repr=False, compare=False)

    @property
    def is_tiled(self) -> bool:
        return self.tiles is not None

    def maps(self, ys: NDArray, xs: NDArray) -> tuple[NDArray | float, NDArray | float]:
        """Level and noise on the grid of rows ``ys`` x columns ``xs``: float32 arrays of shape
        (len(ys), len(xs)), or the two floats for a constant model."""
        tiles = self.tiles
        if tiles is None:
            return self.level, self.noise
        return tiles.map(tiles.level, ys, xs, True), tiles.map(tiles.noise, ys, xs, False)

    def noise_map(self, ys: NDArray, xs: NDArray) -> NDArray | float:
        """The noise alone on the grid of rows ``ys`` x columns ``xs`` (see :meth:`maps`)."""
        tiles = self.tiles
        if tiles is None:
            return self.noise
        return tiles.map(tiles.noise, ys, xs, False)

    def at(self, x: NDArray, y: NDArray) -> tuple[NDArray, NDArray]:
        """Level and noise at points (x, y) (arrays of one shape), bilinearly interpolated."""
        tiles = self.tiles
        if tiles is None:
            shape = np.shape(x)
            return np.full(shape, self.level), np.full(shape, self.noise)
        level, noise = tiles.at_points(x, y, slice(0, 2))
        return level, noise

    def level_at(self, x: NDArray, y: NDArray) -> NDArray:
        """The level alone at points (x, y) (see :meth:`at`)."""
        tiles = self.tiles
        if tiles is None:
            return np.full(np.shape(x), self.level)
        return tiles.at_points(x, y, slice(0, 1))[0]

    def clutter_at(self, x: NDArray, y: NDArray) -> NDArray:
        """Clutter ratio at points (x, y): 1 on clean sky, larger on structure."""
        tiles = self.tiles
        if tiles is None:
            return np.ones(np.shape(x))
        return tiles.at_points(x, y, slice(2, 3))[0]


def global_background(image: NDArray) -> BackgroundModel:
    """A constant background model from a subsample of the whole image.

    Parameters
    ----------
    image : ndarray, shape (H, W)
        NaN pixels are left out.
    """
    sample = _finite(strided_sample(image)[0])
    if sample.size == 0:  # the finite pixels are sparse: take them all
        sample = _finite(image)
    if sample.size == 0:
        return BackgroundModel(level=0.0, noise=0.0)
    level, noise = clipped_level_noise(sample, quantization_step(sample))
    return BackgroundModel(level=level, noise=noise)


def _finite(values: NDArray) -> NDArray:
    """The finite values, flattened (``values`` itself, raveled, when all are: read, not written)."""
    values = values.ravel()
    if np.issubdtype(values.dtype, np.integer):
        return values
    finite = np.isfinite(values)
    return values if finite.all() else values[finite]


def tiled_background(image: NDArray, tile: int, scale: float = 1.0, offset: float = 0.0,
                     skewed: bool = False) -> BackgroundModel:
    """A background model on a grid of ``tile`` x ``tile`` pixel tiles.

    Parameters
    ----------
    image : ndarray, shape (H, W)
        NaN pixels are left out; a tile without any other takes its nearest neighbour's
        values, and so does a tile of fill (:func:`fill_tiles`).
    tile : int
        Tile side in pixels of ``image``; the grid has max(1, H // tile) x max(1, W // tile)
        tiles of equal size, the last H % tile rows (W % tile columns) are left out.
    scale, offset : float
        Coordinates of the returned tile centres are ``offset + scale * (centre in image)``,
        so that a model measured on a binned image is evaluated in full-resolution pixels.
    skewed : bool
        The frame's low side is clipped (:func:`low_side_clipped`): scale the noise to the
        width of its upper half (:func:`upper_tail_factor`).

    Returns
    -------
    BackgroundModel
        ``level`` is the median of the tile levels, ``noise`` the lower quartile of the tile
        noises (:data:`CLEAN_SKY_QUANTILE`).
    """
    layout = tile_layout(image.shape, tile)
    rows, cols, centres_y, centres_x = layout.rows, layout.cols, layout.centres_y, layout.centres_x
    lowest, q_lo, median, highest = last_axis_quantiles(_gather(image, rows, cols, layout.grid),
                                                        (0.0, GAUSS_LO, 0.5, 1.0))
    fill = fill_tiles(lowest, q_lo, median, highest)
    q_lo, median = (_fill_from_nearest(_without(v, fill)) for v in (q_lo, median))
    if not np.isfinite(median).any():
        return global_background(image)
    level, lower_raw = _median3(median, linear=True), _median3(median - q_lo)
    # noise from the residual, so that a gradient across a tile does not count as noise
    keep_map = rows.size == image.shape[0] and cols.size == image.shape[1]
    level_map = np.empty((rows.size, cols.size), np.float32)
    residual = _gather(image, rows, cols, layout.grid, (level, layout.weights), level_map)
    q_lo, q_mid, q_hi = _stack_quantiles(residual, (GAUSS_LO, 0.5, GAUSS_HI), fill)
    sky = ~fill  # the frame's noise, level, clean sky and tail from the sky's tiles
    own_noise = 0.5 * (q_hi - q_lo) * (upper_tail_factor(q_lo[sky], q_mid[sky], q_hi[sky]) if skewed else 1.0)
    noise = _median3(own_noise)
    noise_global = _grid_quantile(noise[sky], CLEAN_SKY_QUANTILE)
    if noise_global <= 0:  # quantized, nearly flat tiles: fall back on the global estimate
        noise_global = global_background(image).noise
    clutter, lower_global = clutter_ratios(lower_raw, _median3(q_mid - q_lo), sky)
    noise = np.maximum(noise, tile_noise_floor(own_noise[sky], noise_global))
    tiles = TileGrid(level=level, noise=noise, clutter=clutter,
                     centres_y=offset + scale * centres_y, centres_x=offset + scale * centres_x,
                     clutter_reference=lower_global)
    return BackgroundModel(level=_grid_quantile(level[sky], 0.5), noise=noise_global, tiles=tiles,
                           level_map=level_map if keep_map else None)


def tile_noise_floor(own_noise: NDArray, noise_global: float) -> float:
    """The least noise a tile is given (image units): :data:`MIN_NOISE_RATIO` times the clean sky's,
    a guard against flat or quantized tiles. The clean sky is the lower quartile of the sky tiles'
    ``own_noise`` (K,), before their 3 x 3 median, when that is lower than ``noise_global`` (the
    quartile after it): the median grows every noisy patch (lit cloud) by a tile on each side, and
    where clean sky lies in patches between them, the quartile after it can fall in the cloud and
    would raise every clean tile to 0.7 times the cloud's noise."""
    own = _grid_quantile(own_noise, CLEAN_SKY_QUANTILE)
    return MIN_NOISE_RATIO * (min(own, noise_global) if own > 0 else noise_global)


def clutter_ratios(lower_raw: NDArray, lower_residual: NDArray, sky: NDArray[np.bool_]) -> tuple[NDArray, float]:
    """Per-tile clutter ratio (module docstring) and the clean sky's lower-half width it is
    relative to (image units), from the tiles' lower-half widths (ny, nx) of their raw values
    and of their residual from the interpolated level; ``sky``: the tiles that are not fill.

    A tile is cluttered only when it is busy both ways, each against its own clean sky. The
    Moon's glow widens a tile's raw values, not its residual. A steep ramp widens the residual
    of some tiles, where the interpolated level misses it (at the frame's edges, where the
    smoothing kernel meets the border, and where a few stars pull a tile's median, whose values
    spread over the whole ramp), but the raw values of every tile alike. The width returned is
    the residual's; a JPEG's floor (:func:`with_clutter_floor`) scales the smaller ratio by it,
    exactly so where the two clean skies agree (a sky without a gradient).
    """
    ratios, references = [], []
    for lower in (lower_raw, lower_residual):
        reference = _grid_quantile(lower[sky], CLEAN_SKY_QUANTILE)
        ratios.append(lower / reference if reference > 0 else np.ones_like(lower))
        references.append(reference)
    return np.minimum(*ratios), references[1]


def _grid_quantile(grid: NDArray, q: float) -> float:
    """``np.quantile(grid, q)`` (``np.median`` at 0.5) of a grid of tiles, the same value from
    one partition when it is NaN-free (:func:`.windows.fast_quantile`; numpy's own machinery
    costs more than the partition on a grid this small)."""
    values = grid.ravel()
    if not np.isfinite(values).all():
        return float(np.quantile(values, q))
    return float(fast_median(values)) if q == 0.5 else fast_quantile(values, q)


def low_side_clipped(image: NDArray) -> bool:
    """Whether at least :data:`CLIPPED_FRACTION` of a subsample of ``image`` sits at its lowest
    value: a sensor or a file that clips the dark side of its noise at zero."""
    sample = _finite(strided_sample(image)[0])  # the count over the size is np.mean's value (both exact)
    return bool(sample.size) and int(np.count_nonzero(sample == sample.min())) / sample.size >= CLIPPED_FRACTION


def upper_tail_factor(q_lo: NDArray, q_mid: NDArray, q_hi: NDArray) -> float:
    """How much wider the noise's upper half is than its symmetric width, over the whole frame
    (the median over tiles of ``(q_hi - q_mid) / ((q_hi - q_lo) / 2)``), at least 1.

    Thresholds cut the upper tail. Low-signal frames whose pixels pile up at a clipped zero
    (the openstartracker frames of ``../shared/realdata``) have an upper half wider than the
    lower, and at 5 sigma of the symmetric width such a tail gives many false spots per frame;
    scaling the noise by this factor removes most of them (``benchmarks/detect_realdata.py``
    counts the unconfirmed detections on those frames). (Stars raise the upper quantile as
    well, so the factor is applied only to frames whose low side is clipped.)
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = (q_hi - q_mid) / (0.5 * (q_hi - q_lo))
    ratio = ratio[np.isfinite(ratio)]
    return max(1.0, float(np.median(ratio))) if ratio.size else 1.0


def _median3(grid: NDArray, linear: bool = False) -> NDArray:
    """3 x 3 median filter of a tile grid (a single odd tile is replaced by its neighbours').

    Borders repeat the edge value, or with ``linear`` are padded by linear extrapolation, so
    that a plane (a uniform gradient of the level) passes unchanged up to the border.
    """
    return kernels().median3(_pad_one(grid, linear))


def _pad_one(grid: NDArray, linear: bool) -> NDArray:
    """``grid`` (ny, nx) padded by one cell: ``np.pad(grid, 1, mode="edge")``, or with ``linear``
    ``np.pad(grid, 1, mode="reflect", reflect_type="odd")`` (2 x edge - neighbour; the edge itself
    along an axis of one cell), the same values in the same type, without np.pad's cost (several
    times the filter's own on a grid of tiles)."""
    ny, nx = grid.shape
    out = np.empty((ny + 2, nx + 2), grid.dtype)
    out[1:-1, 1:-1] = grid
    inner = out[:, 1:-1]  # rows first, then columns over the padded rows (np.pad's order)
    if linear and ny > 1:
        inner[0], inner[-1] = 2 * grid[0] - grid[1], 2 * grid[-1] - grid[-2]
    else:
        inner[0], inner[-1] = grid[0], grid[-1]
    if linear and nx > 1:
        out[:, 0], out[:, -1] = 2 * out[:, 1] - out[:, 2], 2 * out[:, -2] - out[:, -3]
    else:
        out[:, 0], out[:, -1] = out[:, 1], out[:, -2]
    return out


def _gather(image: NDArray, rows: NDArray, cols: NDArray, grid: tuple[int, int],
            level: tuple[NDArray, AxisWeights] | None = None,
            level_map: NDArray[np.float32] | None = None) -> NDArray:
    """The samples ``image[rows] x [cols]`` (:func:`.tile_geometry.tile_rows_cols`) tile by tile,
    shape (ny, nx, n_rows * n_cols), in the image's type; with ``level`` (a level grid and the
    samples' weights between its tile centres, :func:`.tile_geometry.residual_weights`), their
    residuals from the level interpolated bilinearly (extrapolated beyond the outer centres,
    :func:`.tile_geometry.axis_weights`), which is also written to ``level_map`` (shape
    (len(rows), len(cols)), allocated when None) -- one compiled pass
    (:func:`.frame_kernels.gather_tiles`, :func:`.frame_kernels.gather_residuals`)."""
    ny, nx = grid
    size = (rows.size // ny) * (cols.size // nx)
    if level is None:
        return kernels().gather_tiles(image, rows, cols, np.empty((ny, nx, size), image.dtype))
    values, (y0, y1, wy, x0, x1, wx) = level
    out = np.empty((ny, nx, size), np.result_type(image.dtype, np.float32))
    level_map = np.empty((rows.size, cols.size), np.float32) if level_map is None else level_map
    return kernels().gather_residuals(image, rows, cols, values.astype(np.float32), y0, y1, wy, x0, x1, wx, out,
                                      level_map)


def _tile_samples(image: NDArray, tile: int) -> tuple[NDArray, NDArray, NDArray]:
    """The subsample of every tile (:func:`.tile_geometry.tile_rows_cols`) as one array (ny * n_rows,
    nx * n_cols) (a view when it is every pixel), and its row and column indices in ``image``."""
    rows, cols = tile_rows_cols(image.shape, tile)
    if rows.size > 1 and cols.size > 1 and rows[1] - rows[0] == 1 and cols[1] - cols[0] == 1:
        return image[: rows.size, : cols.size], rows, cols
    return image[np.ix_(rows, cols)], rows, cols


def _tile_quantiles(sample: NDArray, grid: tuple[int, int], q: tuple[float, ...]) -> list[NDArray]:
    """Quantiles ``q`` of each tile of a :func:`_tile_samples` sample, on the tile ``grid``
    (ny, nx) (see :func:`_stack_quantiles`)."""
    return _stack_quantiles(_gather(sample, np.arange(sample.shape[0]), np.arange(sample.shape[1]), grid), q)


def _stack_quantiles(stack: NDArray, q: tuple[float, ...], fill: NDArray[np.bool_] | None = None) -> list[NDArray]:
    """Quantiles ``q`` of each tile of a :func:`_gather` stack (ny, nx, S), ignoring NaN, each of
    shape (ny, nx); a tile with no finite value, or of ``fill`` (shape (ny, nx)), takes its
    nearest neighbour's (all NaN when no tile has one). The stack is sorted in place."""
    return [_fill_from_nearest(_without(v, fill)) for v in last_axis_quantiles(stack, q)]


FILL_SIGMA = 3.0
"""A tile of one value is fill when it lies this many times the sky's lower-half width below it."""


def fill_tiles(lowest: NDArray, q_lo: NDArray, median: NDArray, highest: NDArray) -> NDArray[np.bool_]:
    """The tiles of fill: one value throughout, the frame's lowest, and more than
    :data:`FILL_SIGMA` times the sky's lower-half width below the sky (the median level of the
    tiles whose values vary): the black borders of a registered or stacked frame, a masked area.
    Left as sky, a quarter of the frame's tiles of fill would make its clean sky noiseless, and
    the noise fall back on the whole frame's, borders included: 20-30 times the sky's.

    Parameters
    ----------
    lowest, q_lo, median, highest : ndarray, shape (ny, nx)
        Each tile's smallest value, its :data:`GAUSS_LO` quantile, median and largest value
        (NaN for a tile without a value).

    Returns
    -------
    ndarray of bool, shape (ny, nx)
        All False when no tile is of one value or every tile is (a noise-free frame's sky is of
        one value, and so are its tiles, at the level of the sky in the tiles with stars).
    """
    constant = lowest == highest  # False for NaN
    varying = np.isfinite(median) & ~constant
    if not constant.any() or not varying.any():
        return np.zeros(median.shape, dtype=bool)
    sky, width = np.median(median[varying]), np.median(median[varying] - q_lo[varying])
    return constant & (lowest <= np.nanmin(lowest)) & (median < sky - FILL_SIGMA * width)


def _without(grid: NDArray, tiles: NDArray[np.bool_] | None) -> NDArray:
    """``grid`` with NaN in ``tiles`` (``grid`` itself when there are none)."""
    return grid if tiles is None or not tiles.any() else np.where(tiles, np.nan, grid)


def last_axis_quantiles(stack: NDArray, q: tuple[float, ...]) -> list[NDArray]:
    """Quantiles along the last axis, NaN left out (linear interpolation, as ``np.quantile``);
    sorting the short rows in place and reading the quantiles off them is faster than
    ``np.nanquantile``, which loops over the rows in Python (``benchmarks/detect_speed.py``
    times the detector; the fine pass's rings use it too). ``stack`` itself is sorted (no copy)."""
    stack.sort(axis=-1)  # NaN go last
    ordered = stack
    if not np.isnan(ordered[..., -1]).any():
        last = stack.shape[-1] - 1
        return [_row_quantile(ordered, quantile * last, last) for quantile in q]
    last = np.sum(~np.isnan(ordered), axis=-1, keepdims=True) - 1
    out = []
    for quantile in q:
        pos = quantile * np.maximum(last, 0)
        lo = np.floor(pos).astype(np.int64)
        low = np.take_along_axis(ordered, lo, axis=-1)
        high = np.take_along_axis(ordered, np.minimum(lo + 1, np.maximum(last, 0)), axis=-1)
        value = low + (pos - lo) * (high - low)
        out.append(np.where(last >= 0, value, np.nan)[..., 0])
    return out


def _row_quantile(ordered: NDArray, pos: float, last: int) -> NDArray:
    """Linear interpolation at position ``pos`` of sorted rows without NaN."""
    lo = int(np.floor(pos))
    hi = min(lo + 1, last)
    return ordered[..., lo] + (pos - lo) * (ordered[..., hi] - ordered[..., lo])


def _fill_from_nearest(grid: NDArray) -> NDArray:
    """NaN cells of ``grid`` replaced by the nearest finite cell (unchanged if none is)."""
    missing = np.isnan(grid)
    if not missing.any() or missing.all():
        return grid
    from scipy import ndimage  # here, not at import: few frames have tiles without sky (issue 20)

    index = ndimage.distance_transform_edt(missing, return_distances=False, return_indices=True)
    return grid[tuple(index)]


def pixel_noise(image: NDArray, model: BackgroundModel) -> float:
    """Noise (standard deviation) of single pixels of ``image``, robust to a clipped low side.

    The model's level (in the pixel coordinates of ``image``), rounded to the data's
    quantization step, is subtracted from a subsample, and the upper-half width is measured
    (:func:`clipped_level_noise` with ``upper_half=True``).
    """
    sample, step = strided_sample(image)
    tiles = model.tiles
    level: NDArray | float = model.level
    if tiles is not None:
        level = strided_map(tiles.level, tiles.centres_y, tiles.centres_x, sample.shape, step)
    finite = np.ravel if np.issubdtype(sample.dtype, np.integer) else _finite  # integers are finite (so is the level)
    sample = sample.astype(np.float64)
    q = quantization_step(finite(sample))
    if q == 1:  # np.rint is np.round's value at 0 decimals; rounded in float32, a map's integers are float64's
        level = np.rint(level)
    elif q > 0:
        level = q * np.rint(np.asarray(level, dtype=np.float64) / q)
    residual = finite(sample - level)
    return clipped_level_noise(residual, q, upper_half=True)[1] if residual.size else 0.0


def with_clutter_floor(model: BackgroundModel, floor: float) -> BackgroundModel:
    """The model with its clutter ratios taken relative to a clean sky at least ``floor`` wide
    (image units; :attr:`TileGrid.clutter_reference`): a JPEG flattens its quietest blocks to
    their mean (:mod:`.compression`), and against those any tile with content looks cluttered."""
    tiles = model.tiles
    if tiles is None or not tiles.clutter_reference < floor:
        return model
    scale = tiles.clutter_reference / floor
    return replace(model, tiles=replace(tiles, clutter=tiles.clutter * scale, clutter_reference=floor))


def with_noise_floor(model: BackgroundModel, floor: float) -> BackgroundModel:
    """The model with every noise value raised to at least ``floor``."""
    tiles = None if model.tiles is None else replace(model.tiles, noise=np.maximum(model.tiles.noise, floor))
    return replace(model, noise=max(model.noise, floor), tiles=tiles)
