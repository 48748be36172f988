"""Input handling of the detector: dtypes, colour rule, NaN / inf, bad input, blank frames."""

from __future__ import annotations

import ast
import dataclasses
import pickle
from pathlib import Path

import numpy as np
import pytest
from star_render import random_positions, render_stars

import startrack.detect
from startrack.detect import DetectionSettings, StarDetector, detect, to_single_channel
from startrack.detect._blocks import detect_in_strips
from startrack.detect._pipeline import detect_frame
from startrack.detect._predictive import measure_windows
from startrack.detect._settings import UPPER_LIMITS
from startrack.errors import InvalidInputError
from startrack.results import Detections
from startrack.units import PIXEL

SHAPE = (128, 160)


@pytest.fixture(scope="module")
def field():
    """A 128 x 160 float image with 8 bright stars, and their true positions."""
    rng = np.random.default_rng(11)
    x, y = random_positions(8, SHAPE, margin=12, min_sep=14, rng=rng)
    flux = np.linspace(2000.0, 6000.0, 8)
    image = render_stars(SHAPE, x, y, flux, sigma_px=1.3, background=20.0, read_noise=2.0, rng=rng)
    return image, x, y


def _matched(det: Detections, x, y, tol: float = 0.2 * PIXEL) -> int:
    dist = np.hypot(x[:, None] - det.x[None], y[:, None] - det.y[None])
    return int(np.sum(dist.min(axis=1) < tol)) if len(det) else 0


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.int16, np.int32, np.int64,
                                   np.float32, np.float64])
def test_every_dtype_finds_the_stars(field, dtype):
    image, x, y = field
    scaled = image * (250.0 / image.max()) if dtype == np.uint8 else image
    integer = np.issubdtype(dtype, np.integer)
    array = np.rint(scaled).astype(dtype) if integer else scaled.astype(dtype)
    det = detect(array)
    assert _matched(det, x, y) == len(x)
    assert len(det) == len(x)
    assert (det.width, det.height) == (SHAPE[1], SHAPE[0])


@pytest.mark.parametrize("dtype", [">u2", ">i2", ">i4", ">f4", ">f8"])
def test_big_endian_arrays_give_the_native_detections(field, dtype):
    """astropy.io.fits.getdata returns big-endian arrays; the compiled passes take native ones."""
    image = np.rint(field[0]).astype(np.dtype(dtype).newbyteorder("="))
    native, swapped = detect(image), detect(image.astype(dtype))
    assert len(native) == len(field[1])
    np.testing.assert_array_equal(swapped.x, native.x)  # the same pixels: the same numbers, exactly
    np.testing.assert_array_equal(swapped.y, native.y)
    windows = StarDetector().measure_windows(image.astype(dtype), native.x, native.y).detections
    expected = StarDetector().measure_windows(image, native.x, native.y).detections
    np.testing.assert_array_equal(windows.x, expected.x)  # px, exactly: the same pixels
    np.testing.assert_array_equal(windows.y, expected.y)


def test_result_arrays_have_documented_types(field):
    det = detect(field[0])
    assert det.area_px.dtype == np.int64
    for name in ("x", "y", "flux", "sigma_px", "peak", "elongation"):
        assert getattr(det, name).dtype == np.float64, name
        assert getattr(det, name).shape == (len(det),)
    assert np.all(det.sigma_px > 0) and np.all(det.elongation >= 1.0)
    assert det.noise == pytest.approx(2.0, rel=0.15)
    assert det.background == pytest.approx(20.0, abs=0.5)


def test_nan_and_inf_pixels_are_ignored(field):
    image, x, y = field
    spoiled = image.copy()
    rng = np.random.default_rng(3)
    spoiled[rng.integers(0, SHAPE[0], 300), rng.integers(0, SHAPE[1], 300)] = np.nan
    spoiled[5, 5], spoiled[6, 9] = np.inf, -np.inf
    # a NaN in the wing of the first star: the star is still found, a little less precisely
    spoiled[int(round(y[0])), int(round(x[0])) + 2] = np.nan
    det = detect(spoiled)
    assert np.all(np.isfinite(det.x)) and np.all(np.isfinite(det.flux))
    assert _matched(det, x, y, tol=0.5 * PIXEL) == len(x)


def test_an_all_nan_star_region_does_not_crash(field):
    image, x, y = field
    spoiled = image.copy()
    yc, xc = int(round(y[0])), int(round(x[0]))
    spoiled[yc - 6: yc + 7, xc - 6: xc + 7] = np.nan
    det = detect(spoiled)
    assert _matched(det, x[1:], y[1:]) == len(x) - 1


@pytest.mark.parametrize("value", [0, 7])
@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_constant_image_has_no_detections(value, dtype):
    det = detect(np.full((64, 64), value, dtype=dtype))
    assert len(det) == 0
    assert det.background == pytest.approx(value)


@pytest.mark.parametrize("bad", [
    np.zeros(10), np.zeros((1, 1)), np.zeros((0, 0)), np.zeros((1, 50)), np.zeros((4, 4, 5)),
    np.zeros((2, 3, 4, 5)), np.full((8, 8), np.nan), np.zeros((8, 8), dtype=complex),
    np.array([["a", "b"], ["c", "d"]]),
])
def test_bad_input_raises_invalid_input_error(bad):
    with pytest.raises(InvalidInputError):
        detect(bad)


@pytest.mark.parametrize("settings", [
    {"sigma": 0}, {"sigma": -1}, {"sigma": float("nan")}, {"binning": 0}, {"binning": 1.5},
    {"kernel_px": 2}, {"kernel": "gauss"}, {"background": "local"}, {"tile_px": 0},
    {"min_area_px": 0}, {"max_area_px": 0}, {"max_elongation": 0}, {"uncertainty": "x"},
    {"reject_edge": "yes"}, {"channel": -1}, {"max_stars": 0}, {"min_peak_snr": -1},
])
def test_bad_settings_raise_once_at_construction(settings):
    with pytest.raises(InvalidInputError, match=next(iter(settings))):
        StarDetector(**settings)


@pytest.mark.parametrize("settings, largest", [
    ({"kernel_px": 1_000_001}, "51"), ({"window_half_px": 200_001}, "100"), ({"denoise_sigma_px": 1e6}, "50"),
    ({"diffusion_iterations": 100_000}, "1000"),
])
def test_settings_whose_cost_has_no_end_have_a_largest_value(settings, largest):
    # before: the kernel ran for more than 30 s (then stopped by hand), the window asked for more memory than
    # exists (MemoryError), the Gaussian hung in scipy and the iterations took about half an hour
    (name, value), = settings.items()
    with pytest.raises(InvalidInputError, match=f"{name} must be at most {largest}, got {value!r}"):
        StarDetector(**settings)
    StarDetector(**{name: type(value)(UPPER_LIMITS[name])})  # the limit itself is valid


def test_detect_with_settings_equals_configured_detector(field):
    a = detect(field[0], sigma=8, max_stars=3)
    b = StarDetector(sigma=8, max_stars=3).detect(field[0])
    assert len(a) == 3
    np.testing.assert_array_equal(a.x, b.x)


# --- colour rule ---------------------------------------------------------------------------

def test_colour_rule_sums_rgb_and_ignores_alpha():
    rng = np.random.default_rng(0)
    rgba = rng.integers(0, 256, (6, 7, 4), dtype=np.uint8)
    expected = rgba[..., :3].astype(np.int64).sum(axis=-1)
    assert expected.max() > 255
    for image in (rgba, rgba[..., :3]):
        grey = to_single_channel(image)
        assert grey.shape == (6, 7) and grey.dtype == np.uint16
        np.testing.assert_array_equal(grey, expected)  # no uint8 overflow


@pytest.mark.parametrize(("channel", "index"), [(0, 0), (1, 1), (2, 2), ("r", 0), ("G", 1),
                                                ("b", 2)])
def test_colour_rule_picks_one_plane_in_native_dtype(channel, index):
    rgba = np.random.default_rng(2).integers(0, 65536, (6, 7, 4)).astype(np.uint16)
    plane = to_single_channel(rgba, channel=channel)
    assert plane.dtype == np.uint16
    np.testing.assert_array_equal(plane, rgba[..., index])


def test_colour_rule_grey_alpha_and_single_plane():
    rng = np.random.default_rng(1)
    la = rng.random((5, 4, 2))
    for channel in (None, "g", 1):
        np.testing.assert_array_equal(to_single_channel(la, channel=channel), la[..., 0])
    np.testing.assert_array_equal(to_single_channel(la[..., :1]), la[..., 0])
    grey = la[..., 0]
    assert to_single_channel(grey) is grey
    assert to_single_channel(grey, channel="b") is grey


@pytest.mark.parametrize("channel", [3, -1, 1.0, "alpha", "", True])
def test_colour_rule_rejects_bad_channel(channel):
    for shape in ((4, 4, 4), (4, 4, 3), (4, 4)):
        with pytest.raises(InvalidInputError, match="channel"):
            to_single_channel(np.zeros(shape), channel=channel)


def test_colour_image_detects_like_its_sum(field):
    image, x, y = field
    rgb = np.stack([0.5 * image, 0.3 * image, 0.2 * image], axis=-1)
    det_rgb = detect(rgb)
    det_grey = detect(image)
    np.testing.assert_allclose(det_rgb.x, det_grey.x, atol=1e-6)
    det_green = detect(rgb, channel=1)
    assert _matched(det_green, x, y) == len(x)


def test_missing_half_frame_gives_no_false_stars_at_its_border():
    rng = np.random.default_rng(12)
    counts = []
    for _ in range(3):
        image = rng.normal(10.0, 2.0, (300, 300))
        image[:, :150] = np.nan
        det = detect(image)
        counts.append(len(det))
        assert det.noise == pytest.approx(2.0, rel=0.1)
    assert sum(counts) == 0


# --- saturated stars, empty frames, new settings ----------------------------------------------


def test_saturated_stars_are_found_and_centred():
    x, y = np.array([40.3, 90.8]), np.array([50.6, 70.2])
    image = render_stars((128, 160), x, y, [5e5, 2e4], sigma_px=1.5, background=100.0,
                         read_noise=3.0, rng=4)
    clipped = np.minimum(image, 4095.0).astype(np.uint16)  # a 12-bit ADC: the first star's core
    assert (clipped == 4095).sum() > 9
    for method in ("weighted", "windowed", "mle"):
        det = detect(clipped, centroid=method)
        assert _matched(det, x, y, tol=0.1 * PIXEL) == 2, method


def test_a_frame_without_stars_and_one_of_pure_noise():
    rng = np.random.default_rng(17)
    sky = np.rint(rng.normal(200.0, 6.0, (256, 320))).astype(np.uint16)
    for method in ("weighted", "windowed", "mle"):
        assert len(detect(sky, centroid=method)) <= 1
    for threshold in ("dynamic", "prefilter-window", "prefilter-grid"):
        assert len(detect(sky, threshold=threshold, pixel_sigma=3.0)) <= 1


@pytest.mark.parametrize("settings", [
    {"centroid": "gauss"}, {"threshold": "otsu"}, {"grouping": "flood"}, {"denoise": "median"},
    {"jump_px": 0}, {"target_stars": 0}, {"prefilter_count": 26}, {"min_packing": -1},
    {"smear_px": (1.0,)}, {"smear_px": (np.nan, 1.0)}, {"dark_columns": (-1, 2)},
    {"psf_sigma_px": 0}, {"gain_e_per_adu": -2}, {"window_half_px": 0},
    {"dark_frame": np.zeros(5)}, {"max_block_px": 10}, {"mag_zero_point": float("inf")},
])
def test_bad_new_settings_raise(settings):
    with pytest.raises(InvalidInputError, match=next(iter(settings))):
        StarDetector(**settings)


def test_settings_show_the_dark_frame_as_its_shape():
    settings = StarDetector(dark_frame=np.zeros((4, 5))).settings()
    assert settings["dark_frame"] == "array(4, 5)" and settings["centroid"] == "windowed"


# --- the settings object and the facade ------------------------------------------------------


def test_the_detector_is_its_settings_replaced_compared_and_pickled_as_one():
    detector = StarDetector(sigma=8, centroid="mle", dark_frame=np.zeros((4, 5)))
    assert isinstance(detector, DetectionSettings)
    changed = dataclasses.replace(detector, sigma=6)
    assert type(changed) is StarDetector and (changed.sigma, changed.centroid) == (6, "mle")
    assert changed.dark_frame is detector.dark_frame
    assert detector == StarDetector(sigma=8, centroid="mle") != changed  # the dark frame is not compared
    assert detector != DetectionSettings(sigma=8, centroid="mle")  # a facade is not its bare settings
    restored = pickle.loads(pickle.dumps(detector))
    assert type(restored) is StarDetector and restored == detector
    np.testing.assert_array_equal(restored.dark_frame, detector.dark_frame)
    assert repr(changed).startswith("StarDetector(") and "dark_frame" not in repr(changed)
    with pytest.raises(InvalidInputError, match="sigma"):
        dataclasses.replace(detector, sigma=0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        detector.sigma = 4  # type: ignore[misc]


def test_the_stages_run_on_bare_settings_as_the_facade_runs_them(field):
    image, x, y = field
    settings, detector = DetectionSettings(sigma=8, max_stars=5), StarDetector(sigma=8, max_stars=5)
    np.testing.assert_array_equal(detect_frame(settings, image, None).detections.x, detector.detect(image).x)
    tall = np.vstack([image, image])  # 256 rows: two strips of at most 8192 px
    whole = detect_frame(settings, tall, None).detections
    strips = detect_in_strips(dataclasses.replace(settings, max_block_px=8192), tall).detections
    assert len(whole) == 5
    np.testing.assert_allclose(np.sort(strips.x), np.sort(whole.x), atol=0.01 * PIXEL)
    windows = measure_windows(settings, image, x, y, 6).detections
    np.testing.assert_array_equal(windows.x, detector.measure_windows(image, x, y).detections.x)


def test_no_detect_module_but_the_package_imports_the_facade():
    """The stages take a DetectionSettings: only __init__ (the lazy export) names ._detector."""
    importers = []
    for path in sorted(Path(startrack.detect.__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module == "_detector":
                importers.append(path.name)
    assert importers == ["__init__.py"]
