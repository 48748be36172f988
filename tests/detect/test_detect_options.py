"""The selectable stages: pre-filters, region growing, proximity and shape filters, dynamic
threshold, dark / row-reference subtraction, denoising, magnitudes, predictive windows, strips."""

from __future__ import annotations

import tracemalloc
from collections import deque

import numpy as np
import pytest
from star_render import random_positions, render_stars

from startrack.detect import (
    StarDetector,
    calibrate_zero_point,
    detect,
    instrument_magnitude,
    median_frame,
    stack_frames,
    subtract_dark,
)
from startrack.detect import _dark as dark
from startrack.detect import _denoise as denoise
from startrack.detect import _label as label
from startrack.detect import _magnitude as magnitude
from startrack.detect import _prefilters as prefilters
from startrack.detect import _region_grow as region_grow
from startrack.detect import _shape as shape
from startrack.detect._blocks import strip_rows
from startrack.units import PIXEL

SHAPE = (192, 256)


@pytest.fixture(scope="module")
def field():
    rng = np.random.default_rng(5)
    x, y = random_positions(15, SHAPE, margin=15, min_sep=20, rng=rng)
    flux = np.geomspace(2e3, 4e4, 15)
    image = render_stars(SHAPE, x, y, flux, sigma_px=1.3, background=80.0, read_noise=4.0, rng=rng)
    return image, x, y, flux


def _found(det, x, y, tol=0.3 * PIXEL) -> np.ndarray:
    if len(det) == 0:
        return np.zeros(len(x), dtype=bool)
    return np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None]).min(axis=1) < tol


# --- pre-filters and proximity -----------------------------------------------------------------


def test_window_prefilter_counts_the_5x5_neighbourhood():
    rng = np.random.default_rng(0)
    mask = rng.random((40, 50)) < 0.3
    out = prefilters.prefilter_window(mask, 9)
    padded = np.pad(mask, 2)
    counts = sum(padded[dy: dy + 40, dx: dx + 50] for dy in range(5) for dx in range(5))
    np.testing.assert_array_equal(out, mask & (counts >= 9))


def test_grid_prefilter_keeps_whole_dense_tiles():
    mask = np.zeros((12, 12), dtype=bool)
    mask[0:3, 0:3] = True  # 9 in tile (0, 0)
    mask[6, 6] = mask[7, 7] = True  # 2 in tile (1, 1)
    out = prefilters.prefilter_grid(mask, 9)
    np.testing.assert_array_equal(out, mask & (np.arange(12)[:, None] < 5) & (np.arange(12) < 5))


def test_prefilters_reject_noise_and_keep_stars(field):
    image, x, y, _ = field
    for form in ("prefilter-window", "prefilter-grid"):
        det = detect(image, threshold=form, pixel_sigma=2.0, centroid="windowed")
        assert _found(det, x, y).all(), form
        assert len(det) <= len(x) + 2, form
    # without the pre-filter the same single-pixel threshold admits noise clumps
    assert len(detect(image, threshold="prefilter-window", pixel_sigma=2.0, prefilter_count=1,
                      min_area_px=1)) > len(x) + 20


def test_packing_of_a_disc_and_of_a_sparse_clump():
    yy, xx = np.mgrid[0:30, 0:60]
    mask = (xx - 10) ** 2 + (yy - 15) ** 2 <= 25  # a disc, found first (raster order)
    mask |= ((xx + yy) % 2 == 0) & (xx >= 35) & (xx < 46) & (yy >= 16) & (yy < 27)  # checkerboard
    regions = label.label_regions(mask)
    values = prefilters.packing(regions)
    assert values[0] == pytest.approx(1.0, abs=0.1)
    assert values[1] < 0.6
    np.testing.assert_array_equal(values >= 0.7, [True, False])


# --- region growing ----------------------------------------------------------------------------


def _bfs_regions(mask, jump):
    """The seed's scan: every jump-th row and column, breadth-first 4-connected growth."""
    work, found = mask.copy(), []
    for r in range(0, mask.shape[0], jump):
        for c in range(0, mask.shape[1], jump):
            if not work[r, c]:
                continue
            work[r, c], queue, pixels = False, deque([(r, c)]), set()
            while queue:
                i, j = queue.popleft()
                pixels.add((i, j))
                for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                    a, b = i + di, j + dj
                    if 0 <= a < mask.shape[0] and 0 <= b < mask.shape[1] and work[a, b]:
                        work[a, b] = False
                        queue.append((a, b))
            found.append(pixels)
    return found


@pytest.mark.parametrize("jump", [1, 3])
def test_region_growing_equals_the_seed_scan(jump):
    mask = np.random.default_rng(jump).random((40, 45)) < 0.35
    regions = region_grow.grow_regions(mask, jump)
    expected = _bfs_regions(mask, jump)
    assert len(regions) == len(expected)
    for k, pixels in enumerate(expected):  # same regions in the same (scan) order
        got = set(zip(regions.y[regions.index == k], regions.x[regions.index == k], strict=True))
        assert got == pixels


def test_region_grow_grouping_finds_the_stars(field):
    image, x, y, _ = field
    det = detect(image, grouping="region-grow")
    assert _found(det, x, y).all() and len(det) == len(x)


# --- shape and smear ---------------------------------------------------------------------------


def test_spot_shape_of_a_tilted_bar():
    yy, xx = np.mgrid[0:60, 0:60]
    angle = np.radians(30.0)
    along = (xx - 30) * np.cos(angle) + (yy - 30) * np.sin(angle)
    across = -(xx - 30) * np.sin(angle) + (yy - 30) * np.cos(angle)
    regions = label.label_regions((np.abs(along) <= 10) & (np.abs(across) <= 1.5))
    result = shape.spot_shape(regions)
    assert result.angle_deg[0] == pytest.approx(30.0, abs=2.0)
    assert result.major_px[0] == pytest.approx(21.0, abs=1.5)
    assert result.minor_px[0] == pytest.approx(4.0, abs=1.5)


def test_smear_test_accepts_the_expected_streak_only():
    spots = shape.SpotShape(np.array([12.0, 12.0, 3.0]), np.array([3.0, 3.0, 3.0]),
                            np.array([30.0, -60.0, 0.0]))
    smear = (9.0 * np.cos(np.radians(30)), 9.0 * np.sin(np.radians(30)))
    np.testing.assert_array_equal(shape.smear_ok(spots, smear, 2.0, None, 30.0),
                                  [True, False, False])
    np.testing.assert_array_equal(shape.smear_ok(spots, None, 2.0, 5.0, 30.0),
                                  [False, False, True])


def test_detector_keeps_streaks_along_the_predicted_smear():
    xs = np.linspace(100.0, 110.0, 30)
    image = render_stars(SHAPE, xs, np.full(30, 90.0), np.full(30, 600.0), sigma_px=1.0,
                         background=50.0, read_noise=2.0, rng=3)
    kw = {"max_elongation": None}
    kw["smear_tolerance_px"] = 3.0  # the streak's ends taper: a - b is a little under 10 px
    assert len(detect(image, smear_px=(9.0, 0.0), **kw)) == 1
    assert len(detect(image, smear_px=(0.0, 9.0), **kw)) == 0  # wrong direction
    assert len(detect(image, max_axis_difference_px=3.0, **kw)) == 0


# --- dynamic threshold -------------------------------------------------------------------------


def test_dynamic_threshold_targets_the_star_count(field):
    image, x, y, flux = field
    details = StarDetector(threshold="dynamic", target_stars=6).detect_details(image)
    assert len(details) == 6 and details.k_sigma > 5.0
    brightest = np.argsort(-flux)[:6]
    assert _found(details.detections, x[brightest], y[brightest]).all()
    loose = StarDetector(threshold="dynamic", target_stars=100).detect_details(image)
    assert loose.k_sigma == 5.0 and len(loose) == len(x)


# --- dark frames, row reference, denoising, stacking --------------------------------------------


def test_median_dark_removes_hot_pixels(field):
    image, x, y, _ = field
    rng = np.random.default_rng(8)
    pattern = np.zeros(SHAPE)
    hot = rng.integers(0, SHAPE[0], 60), rng.integers(0, SHAPE[1], 60)
    for dy in (0, 1):  # 2 x 2 warm blocks: the hot-pixel and area filters keep them
        for dx in (0, 1):
            pattern[np.minimum(hot[0] + dy, SHAPE[0] - 1), np.minimum(hot[1] + dx, SHAPE[1] - 1)] = \
                rng.uniform(200, 2000, 60)
    darks = [pattern + 80 + rng.normal(0, 4.0, SHAPE) for _ in range(5)]
    frame = image + pattern
    assert len(detect(frame)) > len(x) + 10
    det = detect(frame, dark_frame=median_frame(darks))
    assert _found(det, x, y).all() and len(det) == len(x)
    assert subtract_dark(frame, pattern).dtype == np.float32
    with pytest.raises(ValueError, match="dark_frame"):
        detect(frame, dark_frame=np.zeros((5, 5)))


def test_a_dark_frames_missing_pixels_leave_those_pixels_out(field):
    """NaN or infinite dark pixels gave warnings (inf - inf) and an infinite offset before; now the
    image is NaN there (left out, as its own NaN pixels are) and the stars are found as without them."""
    image, x, y, _ = field
    dark_frame = np.full(SHAPE, 50.0)
    dark_frame[3, 4], dark_frame[10, 20], dark_frame[30:32, :] = np.inf, -np.inf, np.nan
    out = subtract_dark(image, dark_frame)
    assert np.isnan(out[3, 4]) and np.isnan(out[31, 7]) and np.isfinite(out[5, 5])
    np.testing.assert_allclose(out[5, 5], image[5, 5], atol=1e-3)  # counts: the median (50) added back
    assert _found(detect(image, dark_frame=dark_frame), x, y).all()


def test_row_reference_columns_remove_row_offsets(field):
    image, x, y, _ = field
    offsets = np.random.default_rng(9).normal(0, 40.0, SHAPE[0])[:, None]
    frame = np.concatenate([np.full((SHAPE[0], 3), 80.0), image, np.full((SHAPE[0], 5), 80.0)],
                           axis=1) + offsets
    det = detect(frame, dark_columns=(3, 5))
    assert _found(det, x + 3, y).all() and len(det) == len(x)
    assert det.width == SHAPE[1] + 8
    cleaned = dark.subtract_row_reference(frame, 3, 5)
    assert cleaned.shape == SHAPE and np.std(np.median(cleaned, axis=1)) < 1.0


@pytest.mark.parametrize("method", ["gaussian", "diffusion"])
def test_denoising_lowers_the_noise_and_keeps_the_stars(field, method):
    image, x, y, _ = field
    flat = np.random.default_rng(10).normal(100.0, 5.0, (64, 64))
    out = (denoise.gaussian_smooth(flat, 1.0) if method == "gaussian"
           else denoise.anisotropic_diffusion(flat, 10, 15.0))
    assert np.std(out) < 0.6 * np.std(flat)
    det = detect(image, denoise=method)
    assert _found(det, x, y, tol=0.5 * PIXEL).all()


def test_stacking_divides_the_noise():
    rng = np.random.default_rng(11)
    frames = rng.normal(10.0, 4.0, (16, 50, 50))
    assert np.std(stack_frames(frames)) == pytest.approx(1.0, rel=0.1)
    assert np.std(stack_frames(frames, "median")) < 1.5
    with pytest.raises(ValueError, match="method"):
        stack_frames(frames, "max")


# --- magnitudes ---------------------------------------------------------------------------------


def test_zero_point_calibration_against_a_catalog():
    catalog = np.array([3.0, 4.0, 5.0, 6.0, 2.0])
    flux = 10 ** (-0.4 * (catalog - 21.5))
    flux[-1] *= 0.2  # a saturated star reads too faint
    zp, scatter = calibrate_zero_point(flux, catalog)
    assert zp == pytest.approx(21.5, abs=1e-9) and scatter < 0.1
    np.testing.assert_allclose(instrument_magnitude(flux[:4], zp), catalog[:4])
    assert np.isnan(instrument_magnitude([-1.0])[0])
    assert magnitude.jacobs1995_brightness(100.0, 10, 2.0) == pytest.approx(140.0)
    with pytest.raises(ValueError, match="catalog_mag"):
        calibrate_zero_point([1.0, 2.0], [1.0])


# --- predictive windows ------------------------------------------------------------------------


def test_predictive_windows_find_the_predicted_stars(field):
    image, x, y, _ = field
    rng = np.random.default_rng(12)
    px, py = x + rng.uniform(-1.5, 1.5, x.size), y + rng.uniform(-1.5, 1.5, y.size)
    px, py = np.append(px, 128.0), np.append(py, 5.0)  # a prediction with no star
    for method in ("windowed", "mle", "weighted"):
        result = StarDetector(centroid=method).measure_windows(image, px, py, 6)
        assert len(result) == len(x), method
        det = result.detections
        np.testing.assert_allclose(det.x, x[result.window_index], atol=0.1 * PIXEL)
        np.testing.assert_allclose(det.y, y[result.window_index], atol=0.1 * PIXEL)
        assert np.all(np.diff(det.flux) <= 0)


def test_predictive_windows_on_colour_and_nan_and_bad_input(field):
    image, x, y, _ = field
    colour = np.repeat((image / 3.0)[:, :, None], 3, axis=2)
    colour[int(y[0]), int(x[0]) + 3] = np.nan
    result = StarDetector().measure_windows(colour, x, y)
    assert len(result) == len(x)
    with pytest.raises(ValueError, match="half_width_px"):
        StarDetector().measure_windows(image, x, y, 1)
    with pytest.raises(ValueError, match="x and y"):
        StarDetector().measure_windows(image, x, y[:3])
    assert len(StarDetector().measure_windows(image, [], [])) == 0


# --- large frames in strips --------------------------------------------------------------------


def test_strips_give_the_single_pass_result():
    rng = np.random.default_rng(13)
    shape = (700, 300)
    x, y = random_positions(40, shape, margin=15, min_sep=20, rng=rng)
    image = render_stars(shape, x, y, np.full(40, 6e3), sigma_px=1.3, background=60.0,
                         read_noise=4.0, rng=rng).astype(np.float32)
    whole = detect(image)
    assert len(strip_rows(700, 300, 40_000, 32)) > 2
    tracemalloc.start()
    strips = detect(image, max_block_px=40_000)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert len(strips) == len(whole) == len(x)
    np.testing.assert_allclose(np.sort(strips.x), np.sort(whole.x), atol=0.01 * PIXEL)
    assert peak < 120 * 40_000  # bytes: bounded by the strip, not by the frame (0.84 Mpx)
