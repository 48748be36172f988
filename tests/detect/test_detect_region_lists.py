"""The compiled loops behind :class:`startrack.detect._label.Regions`' ``select``, ``upsample`` and
``max_of`` and the edge filter ``peak_away_from_edge``, against the numpy computations they
replaced (kept here as the reference): the same arrays, in the same types, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect._filters import EDGE_PEAK_FRACTION, away_from_edge, peak_away_from_edge
from startrack.detect._label import Regions, label_regions


def _numpy_select(regions: Regions, keep: np.ndarray) -> Regions:
    pixel_keep = keep[regions.index]
    index = (np.cumsum(keep) - 1)[regions.index[pixel_keep]]
    counts = regions.counts[keep]
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    return Regions(index, regions.y[pixel_keep], regions.x[pixel_keep], starts[: counts.size])


def _numpy_upsample(regions: Regions, factor: int) -> Regions:
    dy, dx = np.divmod(np.arange(factor * factor), factor)
    y = (regions.y[:, None] * factor + dy).ravel()
    x = (regions.x[:, None] * factor + dx).ravel()
    return Regions(np.repeat(regions.index, factor * factor), y, x, regions.starts * factor * factor)


def _numpy_edge(regions: Regions, values: np.ndarray, shape: tuple[int, int], margin: int, core: np.ndarray,
                max_core_px: int) -> np.ndarray:
    h, w = shape
    top = regions.argmax(values)
    y, x = regions.y[top], regions.x[top]
    inside = (y >= margin) & (x >= margin) & (y < h - margin) & (x < w - margin)
    small = regions.sum(core.astype(np.int64)) <= max_core_px
    bright = ~(values < EDGE_PEAK_FRACTION * values[top][regions.index])  # NaN: every pixel
    return away_from_edge(regions, shape, core & bright) | (inside & small)


def _snr(seed: int, dtype=np.float32) -> np.ndarray:
    """A significance-like image (h, w) with blobs at the borders, ties and NaN holes."""
    rng = np.random.default_rng(seed)
    snr = rng.normal(0.0, 1.5, (61, 47))
    snr[0:3, 10:14] += 9.0  # on the top border
    snr[20:30, 45:47] += 6.0  # on the right border, big
    snr[40, 20:23] = 8.0  # a tie
    snr[5:8, 5:8] = np.nan
    return snr.astype(dtype)


def _same(a: Regions, b: Regions) -> None:
    for name in ("index", "y", "x", "starts"):
        got, expected = getattr(a, name), getattr(b, name)
        assert got.dtype == expected.dtype, name
        np.testing.assert_array_equal(got, expected, err_msg=name)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_region_max_select_upsample_are_the_numpy_values(seed, dtype):
    snr = _snr(seed, dtype)
    regions = label_regions(snr > 2.0)
    peak = regions.max_of(snr)
    expected = regions.max(snr[regions.y, regions.x])
    assert peak.dtype == expected.dtype
    np.testing.assert_array_equal(peak, expected)
    rng = np.random.default_rng(seed)
    for keep in (peak > 4.0, rng.random(len(regions)) < 0.5, np.zeros(len(regions), bool)):
        _same(regions.select(keep), _numpy_select(regions, keep))
    for factor in (2, 3):
        _same(regions.upsample(factor), _numpy_upsample(regions, factor))


def test_region_max_takes_nan():
    image = np.array([[1.0, np.nan, 3.0], [2.0, 2.0, 0.5]])
    regions = Regions(np.array([0, 0, 0, 1, 1, 1]), np.array([0, 0, 0, 1, 1, 1]), np.array([0, 1, 2, 0, 1, 2]),
                      np.array([0, 3]))
    np.testing.assert_array_equal(regions.max_of(image), [np.nan, 2.0])


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("margin, max_core_px", [(0, 0), (1, 4), (2, 64), (3, 1)])
def test_edge_filter_is_the_numpy_one(seed, margin, max_core_px):
    snr = _snr(seed)
    regions = label_regions(snr > 2.0)
    values = snr[regions.y, regions.x]
    if seed == 3:  # ties and a NaN among the values
        values = np.round(values)
        values[regions.starts[1]] = np.nan
    for k in (2.0, 4.0, 8.0):
        core = values > k
        got = peak_away_from_edge(regions, values, snr.shape, margin, core, max_core_px)
        np.testing.assert_array_equal(got, _numpy_edge(regions, values, snr.shape, margin, core, max_core_px))
    assert peak_away_from_edge(regions.select(np.zeros(len(regions), bool)), values[:0], snr.shape, 2,
                               values[:0] > 0, 4).shape == (0,)
