"""RAW files other than 2 x 2 Bayer mosaics: a 6 x 6 X-Trans mosaic, linear DNGs (three colour
planes, as phones write "ProRAW", or a monochrome sensor's), read by read_image at full resolution."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from startrack.camera import Camera
from startrack.cli import main
from startrack.errors import ImageReadError
from startrack.frames import attitude_error, rotation_from_radec_roll
from startrack.io import read_image
from startrack.io._raw import read_raw
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import DEG, PIXEL

from .dng import write_dng, write_linear_dng
from .test_calibrate_raw import HEIGHT, WIDTH, centroids, star_field

rawpy = pytest.importorskip("rawpy")

XTRANS = "GGRGGB/GGBGGR/BRGRBG/GGBGGR/GGRGGB/RBGBRG"
RESPONSE = {"R": 0.4, "G": 1.0, "B": 0.6}
BLACK = 256


def through_filters(light: np.ndarray, pattern: str) -> np.ndarray:
    """``light`` (H, W) as the sites of ``pattern`` (rows joined by "/") record it."""
    rows = pattern.split("/")
    response = np.array([[RESPONSE[c] for c in row] for row in rows])
    reps = (-(-light.shape[0] // response.shape[0]), -(-light.shape[1] // response.shape[1]))
    return light * np.tile(response, reps)[: light.shape[0], : light.shape[1]]


def star_light(rng: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from startrack.simulate import render_gaussian_psf

    x, y = star_field(rng)
    light = render_gaussian_psf((HEIGHT, WIDTH), x, y, np.full(x.size, 4.0e5), 2.0) + 300.0
    return x, y, light


@pytest.mark.parametrize("channel", [None, "g", "r", "b"])
def test_an_xtrans_mosaic_is_read_at_full_resolution(tmp_path, channel):
    x, y, light = star_light(rng=7)
    noise = np.random.default_rng(8).normal(0.0, 2.0, light.shape)
    path = write_dng(tmp_path / "xtrans.dng", np.round(through_filters(light, XTRANS) + BLACK + noise),
                     pattern=XTRANS.lower(), black=(BLACK,))
    image = read_image(path, channel=channel)
    assert image.data.shape == (HEIGHT, WIDTH) and image.mosaic == XTRANS and image.colour
    sky = 300.0 * (RESPONSE[channel.upper()] if channel else 0.25 * (0.4 + 0.6) + 0.5)
    assert abs(np.median(image.data) - sky) < 2.0  # counts: the black level gone, the sky one level
    cx, cy = centroids(image.data - sky, x, y, half=6)
    np.testing.assert_allclose(cx, x, atol=0.03 * PIXEL)
    np.testing.assert_allclose(cy, y, atol=0.03 * PIXEL)


def test_a_linear_dng_is_its_colour_planes_summed(tmp_path):
    x, y, light = star_light(rng=9)
    planes = np.stack([light * RESPONSE[c] for c in "RGB"], axis=-1) + BLACK
    path = write_linear_dng(tmp_path / "proraw.dng", np.round(planes), black=BLACK)
    image = read_image(path)
    assert image.data.shape == (HEIGHT, WIDTH) and image.mosaic is None and image.colour
    one = {c: read_image(path, channel=c).data for c in "rgb"}
    np.testing.assert_allclose(one["r"], np.round(planes[..., 0]) - BLACK)
    np.testing.assert_allclose(image.data, one["r"] + one["g"] + one["b"])
    cx, cy = centroids(image.data - np.median(image.data), x, y, half=6)
    np.testing.assert_allclose(cx, x, atol=0.02 * PIXEL)


def test_a_monochrome_dng_is_read_as_it_is(tmp_path):
    _, _, light = star_light(rng=10)
    path = write_linear_dng(tmp_path / "mono.dng", np.round(light) + BLACK, black=BLACK)
    image = read_image(path)
    assert image.mosaic is None and not image.colour
    np.testing.assert_allclose(image.data, np.round(light))


def test_cell_sums_are_refused_for_other_than_a_bayer_mosaic(tmp_path):
    path = write_dng(tmp_path / "xtrans.dng", np.full((HEIGHT, WIDTH), 600), pattern=XTRANS.lower(), black=(0,))
    with pytest.raises(ImageReadError, match="cell sums need a 2 x 2 Bayer mosaic.*GGRGGB/"):
        read_raw(path)
    path = write_linear_dng(tmp_path / "proraw.dng", np.full((HEIGHT, WIDTH, 3), 600))
    with pytest.raises(ImageReadError, match="cell sums need a 2 x 2 Bayer mosaic.*colour planes"):
        read_raw(path)


def test_a_pattern_that_cannot_be_evened_out_is_refused(tmp_path):
    stripes = "RRRGGGBBB/RRRGGGBBB/RRRGGGBBB/RRRGGGBBB/RRRGGGBBB/RRRGGGBBB/RRRGGGBBB/RRRGGGBBB/RRRGGGBBB"
    path = write_dng(tmp_path / "stripes.dng", np.full((72, 90), 600), pattern=stripes.lower(), black=(0,))
    with pytest.raises(ImageReadError, match="stripes.dng: the colour-filter pattern leaves"):
        read_image(path)


def test_solve_reads_an_xtrans_photo_with_hot_pixels(tmp_path):
    """A simulated 20 deg frame through the X-Trans filters, 0.05 % of its sites hot: `startrack
    solve` names the pattern on stderr and puts the boresight within 2 px of the truth."""
    camera = Camera.from_fov(960, 720, 20.0)
    truth = rotation_from_radec_roll(83 * DEG, -5 * DEG, 20 * DEG)
    sim = simulate_frame(camera, truth, max_mag=7.0, sensor=get_sensor_preset("generic-cmos"), rng=4)
    counts = through_filters(sim.image.astype(np.float64), XTRANS)
    rng = np.random.default_rng(5)
    n_hot = counts.size // 2000
    counts[rng.integers(0, counts.shape[0], n_hot), rng.integers(0, counts.shape[1], n_hot)] += 20000.0
    path = write_dng(tmp_path / "photo.dng", np.clip(np.round(counts), 0, 65535), pattern=XTRANS.lower(), black=(0,))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["solve", str(path), "--json"])
    assert code == 0, err.getvalue()
    assert f"a colour-filter mosaic (pattern {XTRANS}): read at full resolution" in err.getvalue()
    solution = json.loads(out.getvalue())
    solved = rotation_from_radec_roll(solution["ra_deg"] * DEG, solution["dec_deg"] * DEG, solution["roll_deg"] * DEG)
    assert attitude_error(solved, truth) < 2 * PIXEL * camera.pixel_scale_arcsec / 3600 * DEG


def test_margins_are_left_out_of_the_image_and_of_the_web_tools_size_check(tmp_path):
    """A sensor with masked margins (DNG ActiveArea): the image and the web tool's size check both
    have the visible size (the web tool gave the sensor's whole width and height before)."""
    from startrack.web._uploads import image_size

    mosaic = np.round(through_filters(np.full((130, 194), 800.0), "RG/GB")) + BLACK
    path = write_dng(tmp_path / "margins.dng", mosaic, pattern="rggb", black=(BLACK,) * 4,
                     active_area=(2, 4, 128, 190))
    image = read_image(path, channel="r")
    assert image.data.shape == (126, 186) and image.mosaic == "RGGB"
    np.testing.assert_allclose(image.data, 800.0 * RESPONSE["R"], atol=0.5)  # counts
    assert image_size(path, "raw", "margins.dng") == (186, 126)


def test_filters_other_than_red_green_and_blue_are_refused_by_name(tmp_path):
    path = write_dng(tmp_path / "cygm.dng", np.full((64, 96), 500), pattern="cygm", black=(0,))
    named = r"cygm.dng: its sensor's filters read '[CMYG]{2}/[CMYG]{2}', not red, green and blue"
    with pytest.raises(ImageReadError, match=named):
        read_image(path)
