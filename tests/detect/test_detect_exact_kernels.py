"""The compiled paths of ``core_shape``, ``low_side_clipped``, ``pixel_noise`` and the quantization
step give the numbers of the numpy expressions they replaced, bit for bit (kept here as the
reference), on every frame type and with NaN pixels."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect import _robust as robust
from startrack.detect._background import _finite, low_side_clipped, pixel_noise, tiled_background
from startrack.detect._centroid import axis_ratio
from startrack.detect._compiled import region_kernels
from startrack.detect._label import Regions, regions_from_index
from startrack.detect._point_source import HALF_MAX_AREA, MIN_SHAPE_PIXELS, core_shape
from startrack.detect._tile_geometry import strided_map


def _numpy_core_shape(regions: Regions, signal: np.ndarray, peak: np.ndarray) -> tuple[np.ndarray, ...]:
    with np.errstate(invalid="ignore", divide="ignore"):
        core = (signal >= (0.5 * peak)[regions.index]).astype(np.float64)
        m = region_kernels().weighted_moments(regions.starts, regions.x.astype(np.float64),
                                              regions.y.astype(np.float64), core)
        area, xx, yy, xy = m[:, 0], m[:, 3] + 1.0 / 12.0, m[:, 4] + 1.0 / 12.0, m[:, 5]
        elongation = axis_ratio(xx, yy, xy)
        fill = area / (4.0 * np.pi * np.sqrt(np.maximum(xx * yy - xy * xy, 0.0)))
    measured = area >= MIN_SHAPE_PIXELS
    return np.sqrt(area / HALF_MAX_AREA), np.where(measured, elongation, 1.0), np.where(measured, fill, 1.0)


def _blobs(seed: int) -> tuple[Regions, np.ndarray, np.ndarray]:
    """80 blobs of 1-60 pixels, round and elongated, a NaN pixel, a flat one, a NaN peak."""
    rng = np.random.default_rng(seed)
    n = 80
    size = rng.integers(1, 60, n)
    index = np.repeat(np.arange(n), size)
    x = rng.integers(0, 11, index.size) + 30 * index
    y = rng.integers(0, 11, index.size)
    stretch = rng.uniform(1.0, 6.0, n)[index]
    signal = 100.0 * np.exp(-((x - 30 * index - 5.0) ** 2 / stretch + (y - 5.0) ** 2) / 4.0)
    signal += rng.normal(0, 3, index.size)
    regions = regions_from_index(index, y, x, n)
    signal = signal[np.argsort(index, kind="stable")]
    s = regions.starts
    signal[s[2]] = np.nan
    signal[s[3]: s[4]] = 7.0
    peak = regions.max(np.nan_to_num(signal))
    peak[5] = np.nan
    return regions, signal, peak


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_core_shape_is_the_numpy_expression_bit_for_bit(seed):
    regions, signal, peak = _blobs(seed)
    got, expected = core_shape(regions, signal, peak), _numpy_core_shape(regions, signal, peak)
    for a, b in zip(got, expected, strict=True):
        assert a.tobytes() == b.tobytes()
    assert (got.elongation > 1.5).any() and (got.fill != 1.0).any()


def _frames() -> list[np.ndarray]:
    """Frames of each type: sky noise clipped at 0 or not, stars, NaN and inf pixels, a sizes
    that a stride does and does not divide."""
    rng = np.random.default_rng(4)
    out = []
    for shape in ((300, 257), (64, 64), (1, 5)):
        sky = rng.normal(rng.uniform(0, 20), rng.uniform(0.5, 8), shape)
        sky[rng.integers(0, shape[0], 9), rng.integers(0, shape[1], 9)] += 500.0
        for values in (np.clip(sky, 0, None), sky + 30.0):
            out += [np.round(values).astype(np.uint16), np.round(values).clip(0, 255).astype(np.uint8),
                    values.astype(np.float32), np.round(values)]
            bad = values.copy()
            bad.reshape(-1)[rng.integers(0, bad.size, max(1, bad.size // 20))] = np.nan
            bad.reshape(-1)[0] = np.inf
            out += [bad, bad.astype(np.float32)]
    return out


@pytest.mark.parametrize("index", range(len(_frames())))
def test_low_side_test_is_the_numpy_expression(index):
    image = _frames()[index]
    for frame in (image, np.stack([image] * 3, axis=-1), image.T, image.astype(np.int16) if image.dtype.kind == "u"
                  else image):
        sample = _finite(robust.strided_sample(frame)[0])
        expected = bool(sample.size) and float(np.mean(sample == sample.min())) >= 0.05
        assert low_side_clipped(frame) is expected
    assert low_side_clipped(np.full((3, 3), np.nan)) is False


def _numpy_pixel_noise(image, model):
    sample, step = robust.strided_sample(image)
    tiles, level = model.tiles, model.level
    if tiles is not None:
        level = strided_map(tiles.level, tiles.centres_y, tiles.centres_x, sample.shape, step)
    finite = np.ravel if np.issubdtype(sample.dtype, np.integer) else _finite
    sample = sample.astype(np.float64)
    q = robust.quantization_step(finite(sample))
    if q > 0:
        level = np.asarray(level, dtype=np.float64)
        level = np.rint(level) if q == 1 else q * np.rint(level / q)
    residual = finite(sample - level)
    return robust.clipped_level_noise(residual, q, upper_half=True)[1] if residual.size else 0.0


@pytest.mark.parametrize("index", range(0, len(_frames()), 2))
@pytest.mark.parametrize("scale", [1, 4])
def test_pixel_noise_is_the_numpy_expression(index, scale):
    image = _frames()[index]
    if image.dtype.kind in "ui":
        image = image * np.asarray(scale, image.dtype)  # a step of 4
    finite = np.asarray(image, np.float32)
    model = tiled_background(np.where(np.isinf(finite), np.nan, finite), 32)
    assert pixel_noise(image, model) == _numpy_pixel_noise(image, model)


def test_quantization_step_past_the_probe():
    """Values whose first 256 distances share a divisor (the probe finds none) and all whose do."""
    rng = np.random.default_rng(5)
    even = 2.0 * rng.integers(0, 50, 600)
    assert robust.quantization_step(even) == 2.0
    even[400] += 1.0
    assert robust.quantization_step(even) == 1.0
    assert robust.quantization_step(np.full(300, 7.0)) == 1.0
