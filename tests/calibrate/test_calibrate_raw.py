"""RAW files through rawpy (LibRaw): a hand-written Bayer DNG with a rendered star field."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.calibrate._ground import time_from_header
from startrack.errors import ImageReadError
from startrack.io import read_image
from startrack.io._raw import cell_origin, full_resolution_xy, read_raw
from startrack.simulate import render_gaussian_psf
from startrack.units import PIXEL

from .dng import write_dng

rawpy = pytest.importorskip("rawpy")

WIDTH, HEIGHT = 192, 144
RESPONSE = {"r": 0.4, "g": 1.0, "b": 0.6}  # relative response of the three filters to the stars
BLACK = (500, 510, 520, 530)


def star_field(rng: int) -> tuple[np.ndarray, np.ndarray]:
    """Full-resolution positions (x, y) of 20 well-separated stars."""
    gen = np.random.default_rng(rng)
    gx, gy = np.meshgrid(np.arange(5), np.arange(4))
    x = 20.0 + 38.0 * gx.ravel() + gen.uniform(-4, 4, gx.size)
    y = 18.0 + 36.0 * gy.ravel() + gen.uniform(-4, 4, gy.size)
    return x, y


def bayer_frame(x, y, pattern: str, rng: int) -> np.ndarray:
    """Counts of a Bayer sensor (black level included) seeing stars at (x, y), PSF sigma 2 px."""
    light = render_gaussian_psf((HEIGHT, WIDTH), x, y, np.full(x.size, 4.0e5), 2.0)
    site = np.array(list(pattern)).reshape(2, 2)
    response = np.vectorize(RESPONSE.get)(site)
    gen = np.random.default_rng(rng)
    cells = (HEIGHT // 2, WIDTH // 2)
    counts = light * np.tile(response, cells) + np.tile(np.reshape(BLACK, (2, 2)), cells)
    return np.round(counts + gen.normal(0.0, 2.0, counts.shape))


def centroids(data: np.ndarray, x_cell: np.ndarray, y_cell: np.ndarray, half: int = 4):
    """Intensity-weighted centroid in a (2 half + 1)^2 window around each rounded position."""
    out = []
    for xc, yc in zip(np.rint(x_cell).astype(int), np.rint(y_cell).astype(int), strict=True):
        win = data[yc - half:yc + half + 1, xc - half:xc + half + 1].astype(float)
        gy, gx = np.mgrid[yc - half:yc + half + 1, xc - half:xc + half + 1]
        out.append(((win * gx).sum() / win.sum(), (win * gy).sum() / win.sum()))
    return np.array(out).T


@pytest.mark.parametrize("pattern", ["rggb", "gbrg"])
@pytest.mark.parametrize("channel", ["g", "r", "b"])
def test_read_raw_puts_the_stars_of_one_colour_where_they_are(tmp_path, pattern, channel):
    x, y = star_field(rng=1)
    path = write_dng(tmp_path / "stars.dng", bayer_frame(x, y, pattern, rng=2), pattern=pattern, black=BLACK)
    image = read_raw(path, channel=channel)
    assert image.data.shape == (HEIGHT // 2, WIDTH // 2)
    assert image.header["raw_cells"] is True
    origin = image.header["raw_origin_xy"]
    site = np.array(list(pattern)).reshape(2, 2)
    rows, cols = np.nonzero(site == channel)
    assert origin == (cols.mean(), rows.mean())
    cx, cy = centroids(image.data, (x - origin[0]) / 2, (y - origin[1]) / 2)
    fx, fy = full_resolution_xy(cx, cy, origin)
    np.testing.assert_allclose(fx, x, atol=0.02 * PIXEL)
    np.testing.assert_allclose(fy, y, atol=0.02 * PIXEL)
    if channel != "g":  # a one-colour site is half a pixel from the cell centre: the origin matters
        assert np.all(np.abs(full_resolution_xy(cx, cy)[0] - x) > 0.4 * PIXEL)


def test_read_raw_sum_subtracts_each_sites_black_level_and_keeps_counts(tmp_path):
    x, y = star_field(rng=3)
    path = write_dng(tmp_path / "stars.dng", bayer_frame(x, y, "rggb", rng=4), pattern="rggb", black=BLACK,
                     exposure_s=2.5, date="2024:03:05 21:10:30")
    total = read_raw(path)
    channels = {c: read_raw(path, channel=c).data for c in "rgb"}
    np.testing.assert_array_equal(total.data, channels["r"] + channels["g"] + channels["b"])
    for data in (total.data, *channels.values()):  # noise only: each site's black level (500-530) is gone
        assert abs(np.median(data)) < 2.0
    flux = {c: channels[c].sum() for c in "rgb"}
    assert flux["g"] / flux["r"] == pytest.approx(2 * RESPONSE["g"] / RESPONSE["r"], rel=0.01)
    # the sum samples at the response-weighted mean site, (0.6 - 0.4) * 0.5 / 3 px from the cell centre
    # towards B: with the centre as origin the star lands that far off, the other way
    origin = total.header["raw_origin_xy"]
    assert origin == (0.5, 0.5)
    cx, cy = centroids(total.data, (x - 0.5) / 2, (y - 0.5) / 2)
    fx, fy = full_resolution_xy(cx, cy, origin)
    colour_shift = (RESPONSE["b"] - RESPONSE["r"]) * 0.5 / (RESPONSE["r"] + 2 * RESPONSE["g"] + RESPONSE["b"])
    np.testing.assert_allclose(fx - x, -colour_shift, atol=0.01 * PIXEL)
    np.testing.assert_allclose(fy - y, -colour_shift, atol=0.01 * PIXEL)
    assert total.header["ExposureTime"] == pytest.approx(2.5)
    assert total.header["DateTimeOriginal"] == "2024:03:05 21:10:30"
    assert time_from_header(total.header, utc_offset_hours=-6).isot == "2024-03-06T03:10:31.250"


def test_cell_origin_and_unreadable_raw(tmp_path):
    rggb = np.array([[0, 1], [3, 2]])
    assert cell_origin(rggb) == (0.5, 0.5)
    assert cell_origin(rggb, "g") == (0.5, 0.5)
    assert cell_origin(rggb, "R") == (0.0, 0.0)
    assert cell_origin(rggb, "b") == (1.0, 1.0)
    bad = tmp_path / "not_raw.dng"
    bad.write_bytes(b"II*\0" + bytes(64))
    with pytest.raises(ImageReadError, match="not a readable RAW"):
        read_raw(bad)


def test_read_image_routes_raw_file_names_through_rawpy(tmp_path):
    mosaic = np.full((64, 96), 600, dtype=np.uint16)
    path = tmp_path / "frame.dng"
    write_dng(path, mosaic)
    image = read_image(path, channel="g")
    assert image.data.shape == (64, 96) and image.mosaic == "RGGB"
    assert "raw_cells" not in image.header


@pytest.mark.parametrize("pattern", ["rggb", "gbrg"])
@pytest.mark.parametrize("channel", [None, "g", "r", "b"])
def test_read_image_puts_a_raw_files_stars_at_full_resolution_where_they_are(tmp_path, pattern, channel):
    """The mosaic at full resolution (startrack.io._mosaic): the rendered stars' centroids in the
    sensor's own pixels, the black levels gone, the pattern named."""
    x, y = star_field(rng=5)
    path = write_dng(tmp_path / "stars.dng", bayer_frame(x, y, pattern, rng=6), pattern=pattern, black=BLACK)
    image = read_image(path, channel=channel)
    assert image.data.shape == (HEIGHT, WIDTH) and image.mosaic == pattern.upper()
    assert abs(np.median(image.data)) < 2.0  # counts: noise only, each site's black level (500-530) gone
    cx, cy = centroids(image.data, x, y, half=6)
    np.testing.assert_allclose(cx, x, atol=0.02 * PIXEL)
    np.testing.assert_allclose(cy, y, atol=0.02 * PIXEL)
