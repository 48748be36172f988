"""Colour-filter arrays of any period read at full resolution (startrack.io._cfa)."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.io._cfa import (
    NEUTRAL_MIX,
    cfa_plane,
    cleaned_block,
    colour_levels,
    pattern_tile,
    phase_indices,
    phase_padded,
    phase_weights,
)
from startrack.io._mosaic import mosaic_luminance, mosaic_plane
from startrack.simulate import render_gaussian_psf
from startrack.units import PIXEL

XTRANS = np.array([[1, 1, 0, 1, 1, 2], [1, 1, 2, 1, 1, 0], [2, 0, 1, 0, 2, 1],
                   [1, 1, 2, 1, 1, 0], [1, 1, 0, 1, 1, 2], [0, 2, 1, 2, 0, 1]])
"""Fujifilm's X-Trans layout (0 R, 1 G, 2 B): 20 green, 8 red and 8 blue sites."""
RGGB = np.array([[0, 1], [1, 2]])
RESPONSE = np.array([0.45, 1.0, 0.6])  # each filter's share of grey light


def colour_map(colours: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    return pattern_tile(colours, (0, 0), shape)


def test_phase_weights_of_a_bayer_pattern_are_the_mosaic_kernel():
    kernel = np.outer([1, 2, 1], [1, 2, 1]) / 16
    weights = phase_weights(RGGB, NEUTRAL_MIX)
    for i in range(2):
        for j in range(2):
            np.testing.assert_allclose(weights[i, j], kernel, atol=1e-7)


def test_every_site_gets_the_neutral_mix_of_colours():
    weights = phase_weights(XTRANS, NEUTRAL_MIX).astype(np.float64)
    for i in range(6):
        for j in range(6):
            around = XTRANS[np.ix_((i + np.arange(-1, 2)) % 6, (j + np.arange(-1, 2)) % 6)]
            shares = [weights[i, j][around == c].sum() for c in range(3)]
            np.testing.assert_allclose(shares, NEUTRAL_MIX, atol=1e-7)


def test_a_pattern_missing_a_colour_around_some_site_is_refused():
    stripes = np.array([[0, 0, 0, 1, 1, 1, 2, 2, 2]])  # columns of one colour, three wide
    with pytest.raises(InvalidInputError, match="leaves"):
        phase_weights(stripes, NEUTRAL_MIX)


def test_phase_indices_continue_the_pattern_past_the_edges():
    index = phase_indices(20, 3, 6)
    assert index.size == 26
    np.testing.assert_array_equal(index[3:-3], np.arange(20))
    assert np.all((index - np.arange(-3, 23)) % 6 == 0)  # the same phase as the missing row
    np.testing.assert_array_equal(phase_indices(5, 1, 2), [1, 0, 1, 2, 3, 4, 3])  # numpy's "reflect" for a period 2


@pytest.mark.parametrize("shape", [(60, 90), (67, 101)])
@pytest.mark.parametrize("origin", [(0, 0), (2, 5)])
def test_flat_light_stays_flat_and_each_colour_is_recovered(shape, origin):
    colours = np.roll(XTRANS, (-origin[0], -origin[1]), axis=(0, 1))
    flat = 1000.0 * RESPONSE[colour_map(colours, shape)]
    np.testing.assert_allclose(cfa_plane(flat, colours), 1000.0 * RESPONSE @ NEUTRAL_MIX, rtol=1e-6)
    for channel in range(3):
        np.testing.assert_allclose(cfa_plane(flat, colours, channel), 1000.0 * RESPONSE[channel], rtol=1e-6)


def test_a_bayer_pattern_reads_as_the_mosaic_kernel_reads_it():
    rng = np.random.default_rng(1)
    data = 800.0 * RESPONSE[colour_map(RGGB, (50, 70))] + rng.normal(0, 5.0, (50, 70))
    np.testing.assert_allclose(cfa_plane(data, RGGB), mosaic_luminance(data), atol=1e-3)  # counts
    np.testing.assert_allclose(cfa_plane(data, RGGB), mosaic_plane(data, "RGGB"), atol=1e-3)


def test_stars_stay_where_they_are():
    """Stars of sd 1.0 px anywhere on the pattern: their centroids within 0.02 px of the truth."""
    rng = np.random.default_rng(2)
    shape = (120, 160)
    x = 20 + 40 * (np.arange(12) % 4) + rng.uniform(-3, 3, 12)
    y = 20 + 40 * (np.arange(12) // 4) + rng.uniform(-3, 3, 12)
    light = render_gaussian_psf(shape, x, y, np.full(12, 5e4), 1.0)
    plane = cfa_plane(light * RESPONSE[colour_map(XTRANS, shape)], XTRANS)
    gy, gx = np.mgrid[:shape[0], :shape[1]]
    for xs, ys in zip(x, y, strict=True):
        win = (np.abs(gx - xs) <= 7) & (np.abs(gy - ys) <= 7)
        w = plane[win]
        assert abs((w * gx[win]).sum() / w.sum() - xs) < 0.02 * PIXEL
        assert abs((w * gy[win]).sum() / w.sum() - ys) < 0.02 * PIXEL


def test_hot_sites_are_replaced_by_their_colour_and_stars_kept():
    rng = np.random.default_rng(3)
    shape = (90, 120)
    sky = 500.0 * RESPONSE[colour_map(XTRANS, shape)]
    star = render_gaussian_psf(shape, np.array([60.3]), np.array([40.6]), np.array([2e5]), 1.5)
    data = sky + star * RESPONSE[colour_map(XTRANS, shape)] + rng.normal(0, 4.0, shape)
    hot = [(10, 10), (70, 33), (0, 5), (89, 119)]  # two on the frame's edges
    for y, x in hot:
        data[y, x] += 4000.0
    plane = cfa_plane(data, XTRANS)
    level = 500.0 * RESPONSE @ NEUTRAL_MIX
    for y, x in hot:
        assert np.abs(plane[max(0, y - 1): y + 2, max(0, x - 1): x + 2] - level).max() < 20.0  # counts; 4000 unreplaced
    assert plane[40, 60] - level > 1000.0  # the star's core kept


def test_strips_give_the_whole_frame_values(monkeypatch):
    import startrack.io._cfa as cfa

    rng = np.random.default_rng(4)
    shape = (45, 50)
    data = 300.0 * RESPONSE[colour_map(XTRANS, shape)] + rng.normal(0, 3.0, shape)
    data[rng.integers(0, 45, 10), rng.integers(0, 50, 10)] += 3000.0
    whole = cfa_plane(data, XTRANS, 1)
    monkeypatch.setattr(cfa, "STRIP_ROWS", 7)
    np.testing.assert_array_equal(cfa_plane(data, XTRANS, 1), whole)


def test_colour_levels_and_noise():
    rng = np.random.default_rng(5)
    shape = (300, 400)
    data = 700.0 * RESPONSE[colour_map(XTRANS, shape)] + rng.normal(0, 6.0, shape)
    levels, noise = colour_levels(data, XTRANS)
    np.testing.assert_allclose(levels, 700.0 * RESPONSE, atol=1.0)  # counts
    assert noise == pytest.approx(6.0, rel=0.1)
    levels, noise = colour_levels(data[:3, :5], XTRANS)  # smaller than a period: no noise to measure
    assert np.isnan(noise)


def test_mosaic_to_plane_reads_a_cameras_array_as_a_file_would_be_read():
    from startrack.io import mosaic_to_plane

    rng = np.random.default_rng(6)
    bayer = 400.0 * RESPONSE[colour_map(RGGB, (40, 50))] + rng.normal(0, 3.0, (40, 50))
    np.testing.assert_array_equal(mosaic_to_plane(bayer, "rggb"), mosaic_plane(bayer, "RGGB"))
    np.testing.assert_array_equal(mosaic_to_plane(bayer, "RGGB", "b"), mosaic_plane(bayer, "RGGB", 2))
    xtrans = 400.0 * RESPONSE[colour_map(XTRANS, (40, 50))] + rng.normal(0, 3.0, (40, 50))
    text = "GGRGGB/GGBGGR/BRGRBG/GGBGGR/GGRGGB/RBGBRG"
    np.testing.assert_array_equal(mosaic_to_plane(xtrans, text, "g"), cfa_plane(xtrans, XTRANS, 1))
    for bad in ("RGGX", "RG/G", "RRGG/RRGG", "", "GGRGGB/GGBGG"):
        with pytest.raises(InvalidInputError, match="a mosaic pattern must be"):
            mosaic_to_plane(bayer, bad)
    with pytest.raises(InvalidInputError, match="2-D array"):
        mosaic_to_plane(bayer[..., None], "RGGB")
    with pytest.raises(InvalidInputError, match="channel"):
        mosaic_to_plane(bayer, "RGGB", "alpha")


def test_a_hot_site_with_no_finite_neighbour_of_its_colour_takes_its_colours_level():
    rng = np.random.default_rng(7)
    shape = (30, 36)
    data = 200.0 * RESPONSE[colour_map(XTRANS, shape)] + rng.normal(0, 2.0, shape)
    red = colour_map(XTRANS, shape) == 0
    y, x = 12, 14
    assert red[y, x]
    window = (slice(y - 2, y + 3), slice(x - 2, x + 3))
    assert red[y - 1: y + 2, x - 1: x + 2].sum() == 1  # no other red site in its 3 x 3
    data[window] = np.where(red[window], np.nan, data[window])  # every red site within 2 px missing ...
    data[y, x] = 5000.0  # ... but the hot one
    levels, noise = colour_levels(data, XTRANS)
    cleaned = cleaned_block(phase_padded(data, 2, XTRANS.shape), (0, 0), XTRANS, levels, noise)  # no RuntimeWarning
    assert abs(cleaned[y, x] - 200.0 * RESPONSE[0]) < 10.0  # counts: the red level, not 5000
