"""WebP, AVIF and BMP files, read through Pillow by their content (not their name)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image as PILImage

from startrack.errors import ImageReadError
from startrack.io import SUPPORTED_FORMATS, pillow_raster_format, read_image
from startrack.web._uploads import sniff

RNG = np.random.default_rng(20261207)
RGB8 = RNG.integers(0, 256, size=(40, 56, 3)).astype(np.uint8)
GREY8 = RNG.integers(0, 256, size=(40, 56)).astype(np.uint8)


def _save(path, array, fmt, **options):
    PILImage.fromarray(array).save(path, format=fmt, **options)
    return path


@pytest.mark.parametrize(("fmt", "options"), [("WEBP", {"lossless": True}), ("BMP", {})])
def test_lossless_colour_files_give_the_sum_and_each_plane_exactly(tmp_path, fmt, options):
    path = _save(tmp_path / "stars.img", RGB8, fmt, **options)  # the name says nothing
    image = read_image(path)
    assert image.colour and image.bit_depth == 8 and image.compression_step == 0.0
    np.testing.assert_array_equal(image.data, RGB8.astype(np.int64).sum(axis=-1))
    for channel, index in (("r", 0), ("g", 1), ("b", 2)):
        np.testing.assert_array_equal(read_image(path, channel=channel).data, RGB8[..., index])


def test_grey_bitmap_stays_grey(tmp_path):
    image = read_image(_save(tmp_path / "grey.bmp", GREY8, "BMP"))
    assert not image.colour and image.data.dtype == np.uint8
    np.testing.assert_array_equal(image.data, GREY8)


@pytest.mark.parametrize("fmt", ["WEBP", "AVIF"])
def test_lossy_files_are_read_close_to_their_pixels(tmp_path, fmt):
    smooth = np.repeat(np.repeat(RGB8[::8, ::8], 8, axis=0), 8, axis=1)  # 8 x 8 blocks: little to lose
    image = read_image(_save(tmp_path / f"lossy.{fmt.lower()}", smooth, fmt, quality=95))
    assert image.colour and image.bit_depth == 8
    error = image.data.astype(float) - smooth.astype(float).sum(axis=-1)
    assert np.median(np.abs(error)) < 12.0  # grey levels of the R + G + B sum (0..765)


@pytest.mark.parametrize("fmt", ["WEBP", "AVIF"])
def test_exif_of_webp_and_avif_is_read_as_a_jpeg_s(tmp_path, fmt):
    exif = PILImage.Exif()
    exif[0x0110] = "StarCam 2"  # Model
    exif.get_ifd(0x8769)[0x9003] = "2026:12:07 22:33:44"  # DateTimeOriginal
    image = read_image(_save(tmp_path / f"exif.{fmt.lower()}", RGB8, fmt, exif=exif))
    assert image.header["Model"] == "StarCam 2"
    assert image.header["DateTimeOriginal"] == "2026:12:07 22:33:44"


@pytest.mark.parametrize(("fmt", "options"), [("WEBP", {"lossless": True}), ("WEBP", {"quality": 80}),
                                              ("AVIF", {}), ("BMP", {})])
@pytest.mark.parametrize("fraction", [0.05, 0.5, 0.95])
def test_truncated_files_are_refused_by_name(tmp_path, fmt, options, fraction):
    whole = _save(tmp_path / "whole.img", RGB8, fmt, **options).read_bytes()
    cut = tmp_path / f"cut.{fmt.lower()}"
    cut.write_bytes(whole[: int(len(whole) * fraction)])
    with pytest.raises(ImageReadError, match=r"cut\.\w+: .*truncated or corrupt"):
        read_image(cut)


def test_signatures_name_each_format_and_nothing_else():
    assert {"WEBP", "AVIF", "BMP"} <= set(SUPPORTED_FORMATS)
    assert pillow_raster_format(b"RIFF\x10\x00\x00\x00WEBPVP8 ") == "WEBP"
    assert pillow_raster_format(b"RIFF\x10\x00\x00\x00WAVEfmt ") is None  # a RIFF of sound
    assert pillow_raster_format(b"\x00\x00\x00\x1cftypavif") == "AVIF"
    assert pillow_raster_format(b"\x00\x00\x00\x1cftypheic") is None  # HEIF's own reader
    assert pillow_raster_format(b"BM\x36\x00\x0c\x00\x00\x00") == "BMP"
    assert pillow_raster_format(b"GIF89a\x00\x00") is None


def test_gif_is_still_refused_naming_what_is_read(tmp_path):
    path = _save(tmp_path / "anim.gif", RGB8, "GIF")
    with pytest.raises(ImageReadError, match="unsupported image format GIF; supported: .*WEBP, AVIF, BMP"):
        read_image(path)


@pytest.mark.parametrize(("fmt", "kind"), [("WEBP", "webp"), ("AVIF", "avif"), ("BMP", "bmp")])
def test_the_web_tool_takes_them_by_content(tmp_path, fmt, kind):
    head = _save(tmp_path / "upload.bin", RGB8, fmt).read_bytes()[:32]
    assert sniff(head, "photo.jpg") == kind
