"""The compiled whole-frame passes (:mod:`startrack.detect._frame_kernels`) against the plain
numpy or scipy computations they replace."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from startrack.detect import _background as background
from startrack.detect import _label as label
from startrack.detect import _smooth as smooth
from startrack.detect import _threshold as threshold
from startrack.detect import _tile_geometry as tile_geometry
from startrack.detect import _windows as windows
from startrack.detect._label import Regions


def _scipy_regions(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(region of each True pixel in raster order, its y, its x) by scipy's 8-connected label."""
    labels, _ = ndimage.label(mask, structure=np.ones((3, 3), dtype=bool))
    y, x = np.nonzero(mask)
    return labels[y, x] - 1, y, x


@pytest.mark.parametrize("shape", [(97, 131), (1, 40), (40, 1), (5, 5)])
@pytest.mark.parametrize("density", [0.0, 0.05, 0.4, 0.7, 1.0])
def test_labels_are_scipys_numbering_and_pixel_order(shape, density):
    mask = np.random.default_rng(3).uniform(size=shape) < density
    regions = label.label_regions(mask)
    index, y, x = _scipy_regions(mask)
    order = np.argsort(index, kind="stable")  # region after region, raster order inside
    np.testing.assert_array_equal(regions.index, index[order])
    np.testing.assert_array_equal(regions.y, y[order])
    np.testing.assert_array_equal(regions.x, x[order])
    np.testing.assert_array_equal(regions.counts, np.bincount(index, minlength=len(regions)))


def test_a_ring_and_a_spiral_are_one_region_each():
    mask = np.zeros((20, 20), dtype=bool)
    mask[2, 2:10] = mask[9, 2:10] = mask[2:10, 2] = mask[2:10, 9] = True  # ring
    mask[12, 12:19] = mask[12:19, 18] = mask[18, 12:19] = mask[14:19, 12] = mask[14, 12:16] = True
    regions = label.label_regions(mask)
    assert len(regions) == 2
    assert regions.counts.sum() == mask.sum()


@pytest.mark.parametrize("linear", [False, True])
def test_grid_median_is_scipys(linear):
    rng = np.random.default_rng(4)
    for shape in ((32, 32), (1, 1), (3, 7), (2, 40), (9, 1), (1, 6)):
        grid = np.round(rng.normal(size=shape) * 2)  # ties
        padded = np.pad(grid, 1, mode="reflect", reflect_type="odd") if linear else np.pad(grid, 1, mode="edge")
        expected = ndimage.median_filter(padded, size=3)[1:-1, 1:-1]
        np.testing.assert_array_equal(background._median3(grid, linear=linear), expected)


@pytest.mark.parametrize("step", [1, 2])
def test_residual_samples_are_the_samples_less_the_interpolated_level(step):
    rng = np.random.default_rng(8)
    image = rng.normal(100.0, 5.0, (70, 90)).astype(np.float32)
    rows, cols = np.arange(0, 64, step), np.arange(0, 80, step)  # 4 x 5 tiles of 16 px
    grid = rng.normal(100.0, 3.0, (4, 5)).astype(np.float32)
    centres_y, centres_x = rows.reshape(4, -1).mean(axis=1), cols.reshape(5, -1).mean(axis=1)
    level_map = np.empty((rows.size, cols.size), np.float32)
    weights = tile_geometry.residual_weights(centres_y, centres_x, rows, cols)
    stack = background._gather(image, rows, cols, (4, 5), (grid, weights), level_map)
    expected_level = tile_geometry.grid_map(grid, centres_y, centres_x, rows, cols, True)
    np.testing.assert_array_equal(level_map, expected_level)
    residual = image[np.ix_(rows, cols)] - expected_level
    tiles = residual.reshape(4, rows.size // 4, 5, cols.size // 5).transpose(0, 2, 1, 3).reshape(4, 5, -1)
    np.testing.assert_array_equal(stack, tiles)


def test_grid_quantiles_are_numpys():
    rng = np.random.default_rng(9)
    for shape in ((32, 32), (1, 1), (2, 3), (5, 7)):
        grid = np.round(rng.normal(size=shape), 1).astype(np.float32)  # ties
        assert background._grid_quantile(grid, 0.25) == float(np.quantile(grid, 0.25))
        assert background._grid_quantile(grid, 0.5) == float(np.median(grid))
        grid[0, 0] = np.nan
        assert np.isnan(background._grid_quantile(grid, 0.25))


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int32, np.float32, np.float64])
@pytest.mark.parametrize("factor", [2, 3])
def test_binning_sums_rows_then_columns_in_float32(dtype, factor):
    image = (np.random.default_rng(5).uniform(0, 250, (61, 47))).astype(dtype)
    h, w = 61 // factor, 47 // factor
    cropped = image[: h * factor, : w * factor]
    rows = cropped[0::factor].astype(np.float32)
    for dy in range(1, factor):
        rows += cropped[dy::factor]
    expected = rows[:, 0::factor].copy()
    for dx in range(1, factor):
        expected += rows[:, dx::factor]
    expected *= np.float32(1.0 / factor**2)
    out = smooth.bin_mean(image, factor)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(out, expected)


@pytest.mark.parametrize(("kernel", "size"), [("binomial", 3), ("box", 5), ("box", 7)])
@pytest.mark.parametrize("shape", [(64, 1024), (9, 5), (2, 3), (1, 1)])
def test_smoothing_is_the_shifted_slice_sum(kernel, size, shape):
    image = np.random.default_rng(6).normal(100.0, 5.0, shape).astype(np.float32)
    weights = smooth.kernel_weights(kernel, size)
    padded = np.pad(image, size // 2, mode="edge")
    rows = padded[: shape[0]] * weights[0]
    for k in range(1, size):
        rows += weights[k] * padded[k: k + shape[0]]
    expected = rows[:, : shape[1]] * weights[0]
    for k in range(1, size):
        expected += weights[k] * rows[:, k: k + shape[1]]
    np.testing.assert_array_equal(smooth.smooth(image, kernel, size), expected)


def test_significance_is_level_and_noise_interpolated():
    rng = np.random.default_rng(7)
    yy, xx = np.mgrid[0:96, 0:160]
    image = (50.0 + 0.05 * xx + 0.02 * yy + rng.normal(0, 2.0, yy.shape)).astype(np.float32)
    model = background.tiled_background(image, 16, scale=2.0, offset=0.5)
    level, noise = model.maps(0.5 + 2 * np.arange(96), 0.5 + 2 * np.arange(160))
    expected = (image.astype(np.float64) - level) / noise
    np.testing.assert_allclose(threshold.significance(image, model, 2), expected, rtol=1e-5, atol=1e-5)
    flat = background.global_background(image)
    np.testing.assert_allclose(threshold.significance(image, flat, 2),
                               (image - flat.level) / flat.noise, rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize("shape", [(96, 160), (20, 160), (20, 20)])
def test_grids_at_points_are_the_bilinear_interpolation(shape):
    """Level (extended linearly beyond the outer tile centres), noise and clutter (held) at points
    inside and outside the frame, against numpy's interpolation with the same axis weights; one
    tile along an axis takes that tile's value."""
    rng = np.random.default_rng(3)
    yy, xx = np.mgrid[0: shape[0], 0: shape[1]]
    image = (50.0 + 0.05 * xx + 0.02 * yy + rng.normal(0, 2.0 + xx / 40.0, yy.shape)).astype(np.float32)
    tiles = background.tiled_background(image, 16, scale=2.0, offset=0.5).tiles
    x, y = rng.uniform(-30, 2 * shape[1] + 30, 200), rng.uniform(-30, 2 * shape[0] + 30, 200)
    x[:3], y[3:5] = np.nan, np.nan  # NaN in, NaN out where the axis has two tiles or more

    def numpy_bilinear(grid, extrapolate):
        y0, y1, ty = tile_geometry.axis_weights(tiles.centres_y, y, True)
        x0, x1, tx = tile_geometry.axis_weights(tiles.centres_x, x, True)
        if not extrapolate:
            ty, tx = np.clip(ty, 0.0, 1.0), np.clip(tx, 0.0, 1.0)
        top = grid[y0, x0] * (1 - tx) + grid[y0, x1] * tx
        return top * (1 - ty) + (grid[y1, x0] * (1 - tx) + grid[y1, x1] * tx) * ty

    got = tiles.at_points(x, y, slice(0, 3))
    with np.errstate(invalid="ignore"):
        for k, (grid, extrapolate) in enumerate([(tiles.level, True), (tiles.noise, False), (tiles.clutter, False)]):
            np.testing.assert_array_equal(got[k], numpy_bilinear(grid, extrapolate))
    assert tiles.noise.min() <= np.nanmin(got[1]) and np.nanmax(got[1]) <= tiles.noise.max()  # held
    if tiles.level.size > 1:
        assert np.nanmin(got[0]) < tiles.level.min() or np.nanmax(got[0]) > tiles.level.max()  # extended


def test_work_arrays_start_apart_from_the_frame_rows():
    frame = np.zeros((8, 1024), np.float32)
    for array in (smooth.scratch_row(1024, frame), smooth.empty_apart((8, 1024), frame)):
        gap = (array.ctypes.data - frame.ctypes.data) % smooth.PAGE_BYTES
        assert 1024 <= gap <= smooth.PAGE_BYTES - 1024  # bytes, modulo 4 KiB
        assert array.size == 1024 or array.shape == (8, 1024)


def test_separable_moments_are_the_weighted_sums():
    rng = np.random.default_rng(8)
    q = rng.normal(size=(2, 5, 7, 7))
    wx, dx, wy, dy = (rng.normal(size=(5, 7)) for _ in range(4))
    ax = np.stack([wx, wx * dx, wx * dx**2], axis=-1)  # (N, S, 3)
    ay = np.stack([wy, wy * dy, wy * dy**2], axis=-1)
    expected = np.einsum("nja,knji,nib->knab", ay, q, ax)
    np.testing.assert_allclose(windows.separable_moments(q, wx, dx, wy, dy), expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(windows.separable_moments(q[0], wx, dx, wy, dy), expected[0], rtol=1e-12,
                               atol=1e-12)


def test_argmax_takes_the_last_of_equal_values_and_nan():
    regions = Regions(index=np.array([0, 0, 0, 1, 1, 2]), y=np.zeros(6, np.int64), x=np.arange(6),
                      starts=np.array([0, 3, 5]))
    values = np.array([2.0, 5.0, 5.0, np.nan, 1.0, -1.0])
    np.testing.assert_array_equal(regions.argmax(values), [2, 3, 5])


@pytest.mark.parametrize("step", [1, 3, 6])
def test_strided_level_map_is_the_grid_map(step):
    """The pixel-noise sample's level (cached axis weights) is the tile grid's map on its rows and columns."""
    rng = np.random.default_rng(9)
    yy, xx = np.mgrid[0:90, 0:150]
    image = (50.0 + 0.05 * xx + 0.02 * yy + rng.normal(0, 2.0, yy.shape)).astype(np.float32)
    tiles = background.tiled_background(image, 16, scale=2.0, offset=0.5).tiles
    shape = (len(range(0, 180, step)), len(range(0, 300, step)))
    expected = tiles.map(tiles.level, step * np.arange(shape[0]), step * np.arange(shape[1]), True)
    for _ in range(2):  # the second time from the cache
        got = tile_geometry.strided_map(tiles.level, tiles.centres_y, tiles.centres_x, shape, step)
        np.testing.assert_array_equal(got, expected)
