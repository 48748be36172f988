"""Bayer-mosaic FITS frames read at full resolution (startrack.io._mosaic)."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits

from startrack.errors import InvalidInputError
from startrack.io import read_image
from startrack.io._mosaic import (
    BAYER_PATTERNS,
    bayer_pattern,
    from_mosaic,
    mosaic_channel,
    mosaic_luminance,
    mosaic_plane,
    site_pattern,
    without_hot_sites,
)

SITE_VALUE = {"R": 300.0, "G": 100.0, "B": 50.0}


def flat_mosaic(pattern: str, shape: tuple[int, int] = (40, 60)) -> np.ndarray:
    """A mosaic of uniform light whose sites read SITE_VALUE by colour, ``pattern`` at pixel (0, 0)."""
    cell = np.array([SITE_VALUE[c] for c in pattern]).reshape(2, 2)
    return np.tile(cell, (shape[0] // 2 + 1, shape[1] // 2 + 1))[:shape[0], :shape[1]]


def write(path, data, **cards):
    header = fits.Header()
    for key, value in cards.items():
        header[key] = value
    fits.PrimaryHDU(data, header).writeto(path)
    return path


@pytest.mark.parametrize("pattern", BAYER_PATTERNS)
@pytest.mark.parametrize("shape", [(40, 60), (41, 57)])
def test_luminance_of_uniform_light_is_flat_for_every_pattern_and_edge(pattern, shape):
    lum = mosaic_luminance(flat_mosaic(pattern, shape))
    expected = (SITE_VALUE["R"] + 2 * SITE_VALUE["G"] + SITE_VALUE["B"]) / 4
    assert lum.shape == shape and lum.dtype == np.float32
    np.testing.assert_allclose(lum, expected, rtol=1e-6)  # no checkerboard left, edges and odd sizes included


@pytest.mark.parametrize("pattern", BAYER_PATTERNS)
def test_channel_of_uniform_light_is_that_colour_everywhere(pattern):
    data = flat_mosaic(pattern, (41, 57))
    for index, colour in enumerate("RGB"):
        np.testing.assert_allclose(mosaic_channel(data, pattern, index), SITE_VALUE[colour], rtol=1e-6)


def test_luminance_keeps_a_star_where_it_is():
    """The kernel is symmetric: the centroid of a star's light does not move (to 1e-4 px)."""
    yy, xx = np.mgrid[0:64, 0:64]
    star = 1000.0 * np.exp(-((xx - 30.3) ** 2 + (yy - 33.7) ** 2) / (2 * 1.2 ** 2))
    lum = mosaic_luminance(star)
    total = lum.sum()
    assert abs((lum * xx).sum() / total - 30.3) < 1e-4
    assert abs((lum * yy).sum() / total - 33.7) < 1e-4


@pytest.mark.parametrize(("cards", "expected"), [
    ({"BAYERPAT": "RGGB"}, "RGGB"),
    ({"BAYERPAT": " bggr "}, "BGGR"),
    ({"BAYERPAT": "RGGB", "XBAYROFF": 1}, "GRBG"),
    ({"BAYERPAT": "RGGB", "YBAYROFF": 1}, "GBRG"),
    ({"BAYERPAT": "RGGB", "XBAYROFF": 1, "YBAYROFF": 3}, "BGGR"),
    ({"BAYERPAT": "RGGB", "XBAYROFF": 2}, "RGGB"),
    ({"BAYERPAT": "RGGB", "XBAYROFF": "x"}, "RGGB"),
    ({"BAYERPAT": "RGGB", "XBAYROFF": True}, "RGGB"),
    ({"BAYERPAT": "T"}, None),
    ({"BAYERPAT": "RGBG"}, None),
    ({"BAYERPAT": 1}, None),
    ({}, None),
])
def test_pattern_from_header(cards, expected):
    assert bayer_pattern(cards) == expected


def test_site_pattern_found_in_a_mosaic_not_in_grey_noise():
    rng = np.random.default_rng(1)
    grey = rng.normal(500.0, 5.0, (300, 400)).round().astype(np.uint16)
    assert not site_pattern(grey)
    assert not site_pattern(np.full((300, 400), 7, np.uint16))  # flat: no noise, never a mosaic
    step = np.zeros((300, 400))  # one site raised: a checkerboard of half the step
    step[::2, ::2] = 16.0  # checkerboard 8 counts, under twice the noise (10 counts)
    assert not site_pattern(grey + step)
    step[::2, ::2] = 24.0  # checkerboard 12 counts, over it
    assert site_pattern(grey + step)
    assert not site_pattern(np.zeros((3, 400)))


def test_a_steep_gradient_without_noise_is_no_mosaic():
    """A noise-free ramp of 7 counts per column and 5 per row: its sites sit at different levels,
    but both diagonals of a cell shift alike."""
    yy, xx = np.mgrid[0:300, 0:400]
    assert not site_pattern((1000.0 + 7.0 * xx + 5.0 * yy).astype(np.float32))
    assert not site_pattern((1000 + 7 * xx + 5 * yy).astype(np.uint16))


@pytest.mark.parametrize("shape", [(1, 1), (1, 5), (2, 2), (3, 3), (2, 100), (100, 2), (5, 7)])
def test_tiny_frames_with_a_pattern_are_read_without_warnings(shape, recwarn):
    data = np.arange(np.prod(shape), dtype=np.float64).reshape(shape)
    plane, pattern = from_mosaic(data, {"BAYERPAT": "RGGB"}, None)
    assert plane.shape == shape and pattern == "RGGB"
    assert from_mosaic(data, {"BAYERPAT": "RGGB"}, 1)[0].shape == shape
    assert from_mosaic(data, {}, None)[1] is None
    assert not recwarn.list


def test_a_mosaic_scaled_to_0_1_is_found_and_a_grey_one_is_not():
    """A float frame scaled to 0..1 (as some stacking software saves): no counts, so no two-count
    floor; the noise alone decides. A noise-free rendering is never a mosaic."""
    rng = np.random.default_rng(7)
    mosaic = (flat_mosaic("RGGB", (200, 300)) + rng.normal(0, 3, (200, 300))) / 65535.0
    assert site_pattern(mosaic.astype(np.float32))
    grey = (rng.normal(100, 3, (200, 300)).round() / 65535.0).astype(np.float32)
    assert not site_pattern(grey)
    yy, xx = np.mgrid[0:200, 0:300]
    assert not site_pattern(np.sin(xx / 30.0) * np.cos(yy / 20.0))


def test_no_grey_frame_is_taken_for_a_mosaic_whatever_its_noise():
    """Integer frames whose noise goes down to 0.3 counts, where the sites' medians fall on whole
    counts and can differ by one: the two-count floor keeps them grey."""
    for seed in range(60):
        rng = np.random.default_rng(seed)
        frame = rng.normal(100.0, rng.uniform(0.3, 20.0), (400, 600)).round().astype(np.uint16)
        assert not site_pattern(frame), seed


def test_read_image_of_a_bayer_fits_is_full_resolution_luminance(tmp_path):
    data = flat_mosaic("RGGB", (40, 60)).astype(np.uint16)
    image = read_image(write(tmp_path / "osc.fits", data, BAYERPAT="RGGB"))
    assert image.mosaic == "RGGB" and image.colour
    assert image.data.shape == (40, 60)
    np.testing.assert_allclose(image.data, 137.5)
    green = read_image(tmp_path / "osc.fits", channel="g")
    np.testing.assert_allclose(green.data, 100.0)


def test_read_image_finds_a_mosaic_without_its_card_but_will_not_pick_a_colour(tmp_path):
    rng = np.random.default_rng(2)
    data = (flat_mosaic("GBRG", (200, 300)) + rng.normal(0, 3, (200, 300))).round().astype(np.uint16)
    path = write(tmp_path / "plain.fits", data)
    image = read_image(path)
    assert image.mosaic == "unknown"
    assert abs(float(np.median(image.data)) - 137.5) < 1.0  # counts: the noise's share of the median
    with pytest.raises(InvalidInputError, match="BAYERPAT"):
        read_image(path, channel="r")


def test_grey_fits_and_arrays_are_read_as_they_are(tmp_path):
    rng = np.random.default_rng(3)
    data = rng.normal(500.0, 5.0, (100, 120)).round().astype(np.uint16)
    image = read_image(write(tmp_path / "grey.fits", data))
    assert image.mosaic is None and image.data.dtype == np.uint16
    np.testing.assert_array_equal(image.data, data)
    mosaic = flat_mosaic("RGGB").astype(np.uint16)
    as_array = read_image(mosaic)  # an array has no header: its pixels are taken as they are
    assert as_array.mosaic is None
    np.testing.assert_array_equal(as_array.data, mosaic)


def sky_with_star(rng, sigma_px: float = 1.0) -> tuple[np.ndarray, tuple[int, int]]:
    """An RGGB mosaic of sky (noise 5 counts) with a star of ``sigma_px`` sd centred on pixel (30, 41)
    (x, y), its light through site responses R 0.5, G 1, B 0.6."""
    yy, xx = np.mgrid[0:80, 0:100]
    response = np.tile(np.array([[0.5, 1.0], [1.0, 0.6]]), (40, 50))
    star = 20000.0 * np.exp(-((xx - 30) ** 2 + (yy - 41) ** 2) / (2 * sigma_px ** 2)) / (2 * np.pi * sigma_px ** 2)
    sky = flat_mosaic("RGGB", (80, 100)) + rng.normal(0, 5.0, (80, 100))
    return sky + star * response, (41, 30)


def test_hot_pixels_of_a_mosaic_take_their_colour_neighbours_and_stars_stay():
    rng = np.random.default_rng(4)
    data, (star_y, star_x) = sky_with_star(rng)
    data[10, 70] += 3000.0  # a hot R site (even row, even column)
    data[61, 21] += 800.0  # a hot B site (odd row, odd column)
    cleaned = without_hot_sites(data)
    assert abs(cleaned[10, 70] - SITE_VALUE["R"]) < 20  # the level of its colour, to 4 sigma (counts)
    assert abs(cleaned[61, 21] - SITE_VALUE["B"]) < 20
    np.testing.assert_array_equal(cleaned[star_y - 3: star_y + 4, star_x - 3: star_x + 4],
                                  data[star_y - 3: star_y + 4, star_x - 3: star_x + 4].astype(np.float32))
    untouched = np.ones(data.shape, bool)
    untouched[10, 70] = untouched[61, 21] = False
    np.testing.assert_array_equal(cleaned[untouched], data[untouched].astype(np.float32))


def test_hot_pixels_go_before_the_kernel_spreads_them(tmp_path):
    rng = np.random.default_rng(5)
    data, _ = sky_with_star(rng)
    data[10, 70] += 3000.0
    image = read_image(write(tmp_path / "hot.fits", np.clip(data, 0, 65535).astype(np.uint16), BAYERPAT="RGGB"))
    around = image.data[8:13, 68:73]
    assert np.ptp(around) < 30  # counts: sky noise, no 3 x 3 blob of 3000 / 16 and more


@pytest.mark.parametrize("shape", [(3, 40), (29, 31), (64, 50)])
def test_the_plane_strip_by_strip_is_the_whole_frames(shape, monkeypatch):
    """Strips of 7 rows (many seams, odd and even starts) give exactly what the whole-frame steps
    give: hot sites replaced, then the kernel or one colour."""
    import startrack.io._mosaic as mosaic

    monkeypatch.setattr(mosaic, "STRIP_ROWS", 7)
    rng = np.random.default_rng(6)
    data = flat_mosaic("GRBG", shape) + rng.normal(0, 5.0, shape)
    n = max(1, data.size // 100)
    data[rng.integers(0, shape[0], n), rng.integers(0, shape[1], n)] += 2000.0
    np.testing.assert_array_equal(mosaic_plane(data), mosaic_luminance(without_hot_sites(data)))
    for channel in range(3):
        np.testing.assert_array_equal(mosaic_plane(data, "GRBG", channel),
                                      mosaic_channel(without_hot_sites(data), "GRBG", channel))


def test_the_words_for_a_mosaic_name_its_kind_and_pattern():
    from startrack.io import describe_mosaic

    assert describe_mosaic("RGGB") == "a colour-filter (Bayer) mosaic (pattern RGGB)"
    assert describe_mosaic("GGRGGB/GGBGGR") == "a colour-filter mosaic (pattern GGRGGB/GGBGGR)"
    assert "no BAYERPAT card" in describe_mosaic("unknown") and "(Bayer)" in describe_mosaic("unknown")
