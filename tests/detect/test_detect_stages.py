"""The detector's stages one by one: robust statistics, background, smoothing, labelling,
deblending, moments, filters."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from star_render import render_stars

from startrack.detect import _background as background
from startrack.detect import _centroid as centroid
from startrack.detect import _deblend as deblend
from startrack.detect import _filters as filters
from startrack.detect import _label as label
from startrack.detect import _robust as robust
from startrack.detect import _smooth as smooth
from startrack.units import PIXEL

# --- robust statistics -----------------------------------------------------------------------


@pytest.mark.parametrize("sigma", [0.6, 1.0, 3.0])
def test_quantized_noise_is_measured_without_integer_steps(sigma):
    rng = np.random.default_rng(0)
    values = np.rint(rng.normal(20.0, sigma, 40000))
    step = robust.quantization_step(values)
    assert step == 1.0
    level, noise = robust.clipped_level_noise(values, step)
    # rounding adds 1/12 DN^2 of variance
    assert noise == pytest.approx(np.sqrt(sigma**2 + 1 / 12), rel=0.05)
    assert level == pytest.approx(20.0, abs=0.03)
    _, plain = robust.clipped_level_noise(values, 0.0)
    if sigma < 1:  # plain quantiles jump between integers
        assert abs(plain - sigma) > abs(noise - sigma)


def test_quantization_step_of_summed_channels_and_floats():
    assert robust.quantization_step(np.array([3.0, 9.0, 12.0, 30.0])) == 3.0
    assert robust.quantization_step(np.array([0.5, 1.0])) == 0.0


def test_upper_half_noise_survives_a_zero_clipped_low_side():
    rng = np.random.default_rng(1)
    values = np.maximum(np.rint(rng.normal(0.5, 4.0, 50000)), 0)
    _, upper = robust.clipped_level_noise(values, 1.0, upper_half=True)
    _, both = robust.clipped_level_noise(values, 1.0)
    assert upper == pytest.approx(4.0, rel=0.1)
    assert both < 0.8 * upper


def test_clipping_ignores_a_few_bright_outliers():
    rng = np.random.default_rng(2)
    values = np.concatenate([rng.normal(100.0, 5.0, 20000), rng.uniform(500, 5000, 400)])
    level, noise = robust.clipped_level_noise(values)
    assert level == pytest.approx(100.0, abs=0.3)
    assert noise == pytest.approx(5.0, rel=0.05)


# --- background ------------------------------------------------------------------------------


def test_tiled_background_follows_a_gradient_and_keeps_the_noise():
    rng = np.random.default_rng(3)
    yy, xx = np.mgrid[0:200, 0:300]
    truth = 50.0 + 0.8 * xx + 0.3 * yy
    model = background.tiled_background(truth + rng.normal(0, 2.0, truth.shape), 32)
    level, noise = model.maps(np.arange(200), np.arange(300))
    assert level.shape == (200, 300)
    error = level - truth  # tile medians of a noisy ramp scatter by a fraction of the noise
    assert np.sqrt(np.mean(error**2)) < 0.25 * 2.0 and np.max(np.abs(error)) < 1.0 * 2.0
    assert model.noise == pytest.approx(2.0, rel=0.1)
    assert np.all(noise < 2.5) and np.all(noise > 1.5)
    point_level, point_noise = model.at(np.array([10.0, 150.5]), np.array([5.0, 100.0]))
    np.testing.assert_allclose(point_level, [truth[5, 10], 50 + 0.8 * 150.5 + 30], atol=2.0)


def test_tiled_background_scale_and_offset_map_binned_to_full_pixels():
    rng = np.random.default_rng(4)
    binned = 10.0 + rng.normal(0, 1.0, (64, 64))
    tiles = background.tiled_background(binned, 16, scale=2.0, offset=0.5).tiles
    assert tiles is not None
    assert tiles.centres_x[0] == pytest.approx(0.5 + 2 * 7.5)  # px
    assert tiles.centres_y[-1] == pytest.approx(0.5 + 2 * (48 + 7.5))  # px


def test_clutter_ratio_is_one_on_stars_and_high_on_structure():
    rng = np.random.default_rng(5)
    image = 100.0 + rng.normal(0, 2.0, (256, 256))
    image[:, 192:] += rng.uniform(-60, 60, (256, 64))  # "tree": large structure both ways
    stars = render_stars((256, 256), [40.0, 60.0, 45.0, 100.0], [40.0, 45.0, 62.0, 150.0],
                         [3e4] * 4, sigma_px=2.0, background=0.0)
    model = background.tiled_background(image + stars, 32)
    clutter = model.clutter_at(np.array([50.0, 100.0, 240.0]), np.array([50.0, 150.0, 100.0]))
    assert clutter[0] < 1.5 and clutter[1] < 1.5
    assert clutter[2] > 5
    assert background.global_background(image).tiles is None


def test_tile_quantiles_leave_nan_out_and_fill_empty_tiles():
    rng = np.random.default_rng(9)
    image = rng.normal(0.0, 1.0, (64, 96))
    image[:, :40] = np.nan  # the first tile of each row is empty, the second partly
    sample, rows, cols = background._tile_samples(image, 32)
    q_lo, median = background._tile_quantiles(sample, (2, 3), (0.25, 0.5))
    tile = image[np.ix_(rows[(rows < 32)], cols[(cols >= 32) & (cols < 64)])]
    expected = np.nanquantile(tile, [0.25, 0.5])
    assert (q_lo[0, 1], median[0, 1]) == pytest.approx(tuple(expected))
    assert median[0, 0] == median[0, 1]  # the empty tile took its neighbour's value
    assert np.isfinite(q_lo).all()


def test_pixel_noise_of_a_clipped_quantized_frame():
    rng = np.random.default_rng(6)
    image = np.maximum(np.rint(rng.normal(1.0, 3.0, (300, 400))), 0).astype(np.uint8)
    model = background.global_background(image.astype(np.float32))
    assert background.pixel_noise(image, model) == pytest.approx(3.0, rel=0.1)


# --- smoothing -------------------------------------------------------------------------------


@pytest.mark.parametrize(("kernel", "size"), [("box", 3), ("binomial", 3), ("binomial", 5)])
def test_smoothing_matches_scipy_and_keeps_constants(kernel, size):
    rng = np.random.default_rng(7)
    image = rng.normal(0, 1, (40, 50)).astype(np.float32)
    weights = smooth.kernel_weights(kernel, size)
    assert weights.sum() == pytest.approx(1.0)
    expected = ndimage.correlate(image, np.outer(weights, weights), mode="nearest")
    np.testing.assert_allclose(smooth.smooth(image, kernel, size), expected, atol=1e-5)
    flat = np.full((10, 12), 7.0, dtype=np.float32)
    np.testing.assert_allclose(smooth.detection_image(flat, 2, kernel, size), 7.0, rtol=1e-6)


def test_bin_mean_of_integers_and_odd_sizes():
    image = np.arange(35, dtype=np.uint16).reshape(5, 7)
    binned = smooth.bin_mean(image, 2)
    assert binned.shape == (2, 3) and binned.dtype == np.float32
    assert binned[0, 0] == pytest.approx((0 + 1 + 7 + 8) / 4)


# --- labelling and deblending ----------------------------------------------------------------


def test_label_regions_agrees_with_scipy():
    rng = np.random.default_rng(8)
    mask = rng.random((60, 70)) > 0.8
    regions = label.label_regions(mask)
    labels, n = ndimage.label(mask, structure=np.ones((3, 3)))
    assert len(regions) == n
    np.testing.assert_array_equal(np.sort(regions.counts), np.sort(np.bincount(labels.ravel())[1:]))
    assert np.all(np.diff(regions.index) >= 0)
    sums = regions.sum(np.ones(regions.index.size))
    np.testing.assert_array_equal(sums, regions.counts)


def test_regions_select_and_upsample():
    mask = np.zeros((10, 10), dtype=bool)
    mask[1, 1] = mask[1, 2] = mask[6, 6] = True
    regions = label.label_regions(mask)
    kept = regions.select(np.array([False, True]))
    assert len(kept) == 1 and kept.y[0] == 6
    full = regions.upsample(2)
    assert list(full.counts) == [8, 4]
    assert set(zip(full.y[full.index == 1], full.x[full.index == 1], strict=True)) == {
        (12, 12), (12, 13), (13, 12), (13, 13)}


def test_label_regions_of_an_empty_mask():
    regions = label.label_regions(np.zeros((5, 5), dtype=bool))
    assert len(regions) == 0 and regions.sum(np.zeros(0)).size == 0


def test_hysteresis_grows_only_detected_regions():
    snr = np.zeros((20, 20))
    snr[5, 5:9] = [3.5, 6.0, 3.5, 3.2]  # detected, grown to 4 pixels
    snr[15, 15] = 4.0  # above the grow level but never above the detection level
    regions = label.hysteresis_regions(snr, detect_sigma=5.0, grow_sigma=3.0)
    assert len(regions) == 1 and regions.counts[0] == 4


def test_split_regions_separates_two_peaks_but_not_one():
    snr = render_stars((40, 60), [20.0, 28.0], [20.0, 21.0], [2000.0, 1000.0], sigma_px=2.0,
                       background=0.0)
    regions = label.label_regions(snr > 3.0)
    assert len(regions) == 1
    split = deblend.split_regions(regions, snr, min_sigma=5.0)
    assert len(split) == 2
    one = render_stars((40, 60), [25.0], [20.0], [2000.0], sigma_px=2.0, background=0.0)
    single = label.label_regions(one > 3.0)
    assert len(deblend.split_regions(single, one, min_sigma=5.0)) == 1


# --- centroid and moments --------------------------------------------------------------------


def _spot_signal(x0, y0, sigma_x, sigma_y, shape=(41, 41)):
    """An anisotropic pixel-sampled Gaussian and the Regions of all its pixels."""
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    image = np.exp(-0.5 * (((xx - x0) / sigma_x) ** 2 + ((yy - y0) / sigma_y) ** 2))
    regions = label.label_regions(image > 1e-6)
    return regions, image[regions.y, regions.x]


def test_weighted_moments_of_an_elongated_spot():
    regions, signal = _spot_signal(20.3, 19.6, 3.0, 1.5)
    spots = centroid.measure_spots(regions, signal)
    assert spots.x[0] == pytest.approx(20.3, abs=1e-3 * PIXEL)
    assert spots.y[0] == pytest.approx(19.6, abs=1e-3 * PIXEL)
    expected = np.sqrt((9.0 + 1 / 12) / (2.25 + 1 / 12))
    assert spots.elongation[0] == pytest.approx(expected, rel=0.01)
    assert spots.flux[0] == pytest.approx(signal.sum())
    assert (spots.peak_x[0], spots.peak_y[0]) == (20, 20)


def test_round_spot_has_elongation_one_and_single_pixel_is_finite():
    regions, signal = _spot_signal(20.0, 20.0, 2.0, 2.0)
    assert centroid.measure_spots(regions, signal).elongation[0] == pytest.approx(1.0, abs=1e-6)
    one = label.label_regions(np.pad(np.ones((1, 1), dtype=bool), 2))
    spots = centroid.measure_spots(one, np.array([5.0]))
    assert spots.elongation[0] == pytest.approx(1.0) and spots.x[0] == 2.0


def test_eq42_values():
    np.testing.assert_allclose(centroid.sigma_eq42([1.0, 10.0, 1e6]),
                               [0.61, 0.11 + 0.5 * 10**-1.3, 0.11], rtol=1e-6)


# --- filters ---------------------------------------------------------------------------------


def test_peak_fraction_tells_hot_pixels_from_stars():
    image = render_stars((30, 30), [10.0], [10.0], [1000.0], sigma_px=1.0, background=5.0)
    image[20, 20] += 500.0
    fraction = filters.peak_fraction(image, np.array([5.0, 5.0]), np.array([10, 20]),
                                     np.array([10, 20]))
    assert fraction[0] < 0.3 and fraction[1] == pytest.approx(1.0)
    np.testing.assert_array_equal(filters.hot_pixel_ok(fraction, 0.75), [True, False])
    assert filters.hot_pixel_ok(fraction, None).all()


def test_area_elongation_flatness_clutter_filters():
    areas = np.array([2, 4, 50])
    np.testing.assert_array_equal(filters.area_ok(areas, 4, 40), [False, True, False])
    np.testing.assert_array_equal(filters.area_ok(areas, 4, None), [False, True, True])
    np.testing.assert_array_equal(filters.elongation_ok(np.array([1.0, 6.0]), 5.0), [True, False])
    np.testing.assert_array_equal(filters.flatness_ok(np.array([0.05, 0.2]), 0.1), [False, True])
    np.testing.assert_array_equal(filters.clutter_ok(np.array([1.0, 3.0]), 2.5), [True, False])
    np.testing.assert_array_equal(filters.peak_ok(np.array([3.0, 8.0]), 5.0), [False, True])


def test_edge_filter_looks_at_the_core_only():
    mask = np.zeros((10, 10), dtype=bool)
    mask[0:3, 4:6] = True  # touches row 0
    mask[5:7, 5:7] = True
    regions = label.label_regions(mask)
    np.testing.assert_array_equal(filters.away_from_edge(regions, mask.shape), [False, True])
    core = regions.y >= 1  # the part on row 0 is only a grown wing
    np.testing.assert_array_equal(filters.away_from_edge(regions, mask.shape, core), [True, True])


def test_ring_quantiles_are_numpys_nanpercentile():
    """The fine pass's rings (some NaN, one all NaN) through background.last_axis_quantiles."""
    rng = np.random.default_rng(4)
    for _ in range(100):
        values = rng.normal(size=(int(rng.integers(1, 40)), int(rng.integers(1, 90)))) * 300.0
        values[rng.uniform(size=values.shape) < rng.uniform(0.0, 0.9)] = np.nan
        values[0] = np.nan  # a ring of masked pixels only
        with np.errstate(all="ignore"), pytest.warns(RuntimeWarning):
            want = np.nanpercentile(values, [15.87, 84.13], axis=1)
        got = np.array(background.last_axis_quantiles(values.copy(), (0.1587, 0.8413)))
        assert np.array_equal(np.isnan(got), np.isnan(want))
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12, equal_nan=True)  # image units
