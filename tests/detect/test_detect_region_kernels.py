"""The per-region compiled loops (:mod:`startrack.detect._region_kernels`) behind
``measure_spots``, ``core_shape``, ``spot_shape`` and the deblender's local peaks, against the
numpy computations (``np.add.reduceat`` and neighbour comparisons) they replace; and the windowed
centroider's PSF width, which reads those measurements."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.detect._centroid import PIXEL_VARIANCE, axis_ratio, measure_spots
from startrack.detect._label import Regions, regions_from_index
from startrack.detect._point_source import HALF_MAX_AREA, MIN_SHAPE_PIXELS, core_shape


def _regions(n: int, seed: int) -> tuple[Regions, np.ndarray]:
    """n blobs of 1-40 pixels with Gaussian signal plus noise (one all negative, one with zeros
    only, one with a NaN, one with tied peaks)."""
    rng = np.random.default_rng(seed)
    size = rng.integers(1, 40, n)
    index = np.repeat(np.arange(n), size)
    x = rng.integers(0, 9, index.size) + 20 * index
    y = rng.integers(0, 9, index.size)
    signal = 100.0 * np.exp(-((x - 20 * index - 4.0) ** 2 + (y - 4.0) ** 2) / 6.0) + rng.normal(0, 5, index.size)
    regions = regions_from_index(index, y, x, n)
    signal = signal[np.argsort(index, kind="stable")]
    s = regions.starts
    signal[s[0]: s[1]] = -np.abs(signal[s[0]: s[1]])
    signal[s[1]: s[2]] = 0.0
    signal[s[2]] = np.nan
    signal[s[3]: s[4]] = 7.0
    return regions, signal


def _numpy_spots(regions: Regions, signal: np.ndarray) -> dict:
    x, y = regions.x.astype(np.float64), regions.y.astype(np.float64)
    w = np.maximum(signal, 0.0)
    total = regions.sum(w)
    with np.errstate(invalid="ignore", divide="ignore"):
        xc, yc = regions.sum(w * x) / total, regions.sum(w * y) / total
        dx, dy = x - xc[regions.index], y - yc[regions.index]
        cxx = regions.sum(w * dx * dx) / total + PIXEL_VARIANCE
        cyy = regions.sum(w * dy * dy) / total + PIXEL_VARIANCE
        cxy = regions.sum(w * dx * dy) / total
        top = regions.argmax(signal)
        n = regions.counts
        mean = regions.sum(signal) / n
        flatness = np.sqrt(np.maximum(regions.sum(signal * signal) / n - mean**2, 0.0)) / signal[top]
    return dict(x=xc, y=yc, weight=total, flux=regions.sum(signal), peak=signal[top], peak_x=regions.x[top],
                peak_y=regions.y[top], elongation=axis_ratio(cxx, cyy, cxy), flatness=flatness,
                spread_px2=regions.sum(np.where(w > 0, dx * dx + dy * dy, 0.0)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spot_measurements_are_the_reduceat_values(seed):
    regions, signal = _regions(60, seed)
    got = measure_spots(regions, signal)
    for name, expected in _numpy_spots(regions, signal).items():
        # px for positions and spreads, image units for fluxes, ratios for the rest
        np.testing.assert_allclose(getattr(got, name), expected, rtol=1e-12, atol=1e-9, err_msg=name)
    assert np.isnan(got.x[1]) and np.isnan(got.peak[2]) and got.peak_x[3] == regions.x[regions.starts[4] - 1]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_core_shape_is_the_reduceat_value(seed):
    regions, signal = _regions(60, seed)
    peak = np.nan_to_num(regions.max(np.nan_to_num(signal)))
    core = (np.nan_to_num(signal, nan=-np.inf) >= 0.5 * peak[regions.index]).astype(np.float64)
    area = regions.sum(core)
    x, y = regions.x.astype(np.float64), regions.y.astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        mx, my = regions.sum(core * x) / area, regions.sum(core * y) / area
        dx, dy = x - mx[regions.index], y - my[regions.index]
        ratio = axis_ratio(regions.sum(core * dx * dx) / area + 1 / 12, regions.sum(core * dy * dy) / area + 1 / 12,
                           regions.sum(core * dx * dy) / area)
    size, elongation, _ = core_shape(regions, signal, peak)
    np.testing.assert_allclose(size, np.sqrt(area / HALF_MAX_AREA), rtol=1e-12)  # px
    np.testing.assert_allclose(elongation, np.where(area >= MIN_SHAPE_PIXELS, ratio, 1.0), rtol=1e-12)  # ratio
    assert (elongation > 1.0).any()


def test_no_regions():
    regions = Regions(*(np.zeros(0, np.int64),) * 4)
    assert measure_spots(regions, np.zeros(0)).x.size == 0
    assert core_shape(regions, np.zeros(0), np.zeros(0))[0].size == 0


def test_local_peaks_are_numpys_neighbour_comparison():
    """Peaks against the clipped-index numpy comparison: plateaus (>=), the border (a pixel is its
    own neighbour there), NaN (never a peak, and no peak beside one) and a threshold that float32
    cannot hold (compared in the image's type)."""
    from startrack.detect._deblend import local_peaks

    rng = np.random.default_rng(4)
    snr = np.round(rng.normal(5.0, 2.0, (40, 50)), 1).astype(np.float32)  # ties
    snr[7, 9] = np.nan
    mask = rng.uniform(size=snr.shape) < 0.5
    yy, xx = np.nonzero(mask)
    regions = regions_from_index(np.zeros(yy.size, np.int64), yy, xx, 1)
    offsets = np.array([(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx])
    ny = np.clip(regions.y[:, None] + offsets[:, 0], 0, 39)
    nx = np.clip(regions.x[:, None] + offsets[:, 1], 0, 49)
    value = snr[regions.y, regions.x]
    threshold = 5.1  # not a float32 value
    expected = (value > np.float32(threshold)) & np.all(value[:, None] >= snr[ny, nx], axis=1)
    got = local_peaks(regions, snr, threshold)
    np.testing.assert_array_equal(got, expected)
    assert 5 < got.sum() < got.size


@pytest.mark.parametrize("with_nan", [False, True])
def test_psf_width_estimate_is_the_median_formula(with_nan):
    """The windowed centroider's PSF width from the brighter half of the spots, as np.median
    gives it (a NaN flux makes numpy's median NaN: no spot counts as bright, the width is 1 px)."""
    from startrack.detect._centroiders import MIN_PSF_SIGMA_PX, SIZE_TO_SIGMA, estimate_psf_sigma

    regions, signal = _regions(60, 5)
    spots = measure_spots(regions, np.nan_to_num(signal))
    if with_nan:
        spots = type(spots)(**{**spots.__dict__, "flux": np.where(np.arange(60) == 7, np.nan, spots.flux)})
    bright = spots.size_px[spots.flux >= np.median(spots.flux)]
    bright = bright[np.isfinite(bright)]
    expected = max(MIN_PSF_SIGMA_PX, SIZE_TO_SIGMA * float(np.median(bright)) if bright.size else 1.0)
    assert estimate_psf_sigma(spots) == expected
    assert (bright.size == 0) == with_nan


@pytest.mark.parametrize("seed", [0, 1])
def test_spot_axes_are_the_reduceat_values(seed):
    """Jacobs 1995 axes against the numpy computation (unweighted moments, extents along and
    across the long axis); directions compared modulo 180 deg."""
    from startrack.detect._shape import spot_shape

    regions, _ = _regions(60, seed)
    x, y = regions.x.astype(np.float64), regions.y.astype(np.float64)
    n = regions.counts
    x0, y0 = regions.sum(x) / n, regions.sum(y) / n
    dx, dy = x - x0[regions.index], y - y0[regions.index]
    angle = 0.5 * np.arctan2(2.0 * regions.sum(dx * dy), regions.sum(dx * dx) - regions.sum(dy * dy))
    c, s = np.cos(angle)[regions.index], np.sin(angle)[regions.index]
    along, across = dx * c + dy * s, -dx * s + dy * c
    got = spot_shape(regions)
    np.testing.assert_allclose(got.major_px, regions.max(along) - regions.min(along) + 1.0, rtol=0, atol=1e-9)  # px
    np.testing.assert_allclose(got.minor_px, regions.max(across) - regions.min(across) + 1.0, rtol=0, atol=1e-9)  # px
    turn = (got.angle_deg - np.degrees(angle) + 90.0) % 180.0 - 90.0
    np.testing.assert_allclose(turn, 0.0, atol=1e-9)  # deg
    assert ((got.angle_deg > -90.0) & (got.angle_deg <= 90.0)).all() and (got.major_px > got.minor_px).any()


def _numpy_hot_measures(image: np.ndarray, level: np.ndarray, px: np.ndarray, py: np.ndarray,
                        noise: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hot-pixel measures as :func:`startrack.detect._filters.peak_fractions` computed them
    with numpy before the compiled loop (the reference of the test below)."""
    from startrack.detect._filters import BLOCK_MIN_SNR, BLOCK_PIXELS, CLUSTER_PIXELS, neighbourhoods_3x3

    ys, xs = neighbourhoods_3x3(image.shape, py, px)
    window = image[ys, xs].astype(np.float64) - level[:, None]
    peak = image[py, px] - level
    total = np.nansum(window, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        single = peak / total
        brightest = -np.sort(-np.nan_to_num(window, nan=-np.inf), axis=1)[:, 1:BLOCK_PIXELS]
        shares = (peak[:, None] + np.cumsum(np.maximum(brightest, 0.0), axis=1)) / total[:, None]
        powered = np.c_[single, shares ** (2.0 ** np.arange(1, BLOCK_PIXELS))]
        cluster = powered[:, :CLUSTER_PIXELS].max(axis=1)
        judged = total[:, None] >= np.multiply.outer(noise, BLOCK_MIN_SNR)
        block = np.maximum(cluster, np.where(judged, powered[:, CLUSTER_PIXELS:], 0.0).max(axis=1))
        positive = total > 0
        return single, np.where(positive, cluster, single), np.where(positive, block, single)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32, np.float64])
def test_hot_measures_are_numpys_to_the_last_bit_of_a_power(dtype):
    """The compiled hot-pixel measures against numpy's: the peak's share exactly (the sum of nine
    in numpy's pairwise order), the powered shares of clusters and blocks to 1 ulp (numpy's SIMD
    power and the C library's pow differ in the last bit of about 5 % of values); spots at the
    border, on hot pixels and pairs, stars of sd 0.3-2 px, NaN pixels, and sums of 0 or below."""
    from startrack.detect._filters import peak_fractions

    rng = np.random.default_rng(3)
    yy, xx = np.mgrid[0:60, 0:70]
    image = rng.normal(100.0, 5.0, (60, 70))
    for x, y, sd, amplitude in zip(rng.uniform(0, 70, 8), rng.uniform(0, 60, 8), rng.uniform(0.3, 2.0, 8),
                                   rng.uniform(200, 5000, 8), strict=True):
        image += amplitude * np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * sd * sd))
    hot_y, hot_x = rng.integers(0, 60, 30), rng.integers(0, 69, 30)
    image[hot_y, hot_x] += 3000.0
    image[hot_y[:15], hot_x[:15] + 1] += 2500.0  # pairs
    image = (np.clip(image / 20.0, 0, 255) if dtype == np.uint8 else image).astype(dtype)
    if np.issubdtype(dtype, np.floating):
        image[rng.integers(0, 60, 25), rng.integers(0, 70, 25)] = np.nan
    px = np.r_[hot_x, rng.integers(0, 70, 50), 0, 69]
    py = np.r_[hot_y, rng.integers(0, 60, 50), 0, 59]
    level = np.r_[rng.normal(float(np.nanmedian(image)), 2.0, px.size - 2), 1e6, -1e6]  # the last two: sums < 0, > 0
    noise = rng.uniform(0.5, 30.0, px.size)
    compiled = peak_fractions(image, level, px, py, noise=noise)
    reference = _numpy_hot_measures(image, level, px, py, noise)
    np.testing.assert_array_equal(compiled.single, reference[0])
    for got, expected in zip(compiled[1:], reference[1:], strict=True):
        np.testing.assert_array_max_ulp(got, expected, maxulp=1)
