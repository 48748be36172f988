"""Reading images: formats, dtypes and bit depths kept, headers, real files."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest
from astropy.io import fits
from PIL import Image as PILImage

from startrack.errors import ImageReadError
from startrack.io import Image, read_image

RNG = np.random.default_rng(20240611)
GREY8 = RNG.integers(0, 256, size=(17, 23)).astype(np.uint8)
GREY16 = RNG.integers(0, 65536, size=(17, 23)).astype(np.uint16)
RGB8 = RNG.integers(0, 256, size=(17, 23, 3)).astype(np.uint8)
RGB16 = RNG.integers(0, 65536, size=(17, 23, 3)).astype(np.uint16)


# --- files written by Pillow and astropy directly (independent of our writers) ----------------
@pytest.mark.parametrize("fmt", ["PNG", "TIFF"])
@pytest.mark.parametrize("array", [GREY8, GREY16], ids=["8bit", "16bit"])
def test_pillow_grey_keeps_values_and_dtype(tmp_path, fmt, array):
    path = tmp_path / f"grey.{fmt.lower()}"
    PILImage.fromarray(array).save(path, format=fmt)
    image = read_image(path)
    assert isinstance(image, Image)
    assert image.data.dtype == array.dtype
    assert image.bit_depth == array.dtype.itemsize * 8
    assert not image.colour
    assert image.path == path
    np.testing.assert_array_equal(image.data, array)


def test_pillow_32bit_grey_png_from_mode_i_becomes_uint16(tmp_path):
    """Pillow versions that decode 16-bit PNGs as mode 'I' (int32) still give uint16."""
    path = tmp_path / "grey16.png"
    PILImage.fromarray(GREY16).save(path)
    with PILImage.open(path) as pil:
        as_mode_i = pil.convert("I")
    from startrack.io._raster import _to_array  # the mode table itself

    data, bits = _to_array(as_mode_i, 16)
    assert data.dtype == np.uint16 and bits == 16
    np.testing.assert_array_equal(data, GREY16)


def _rgb_sum(rgb: np.ndarray) -> np.ndarray:
    """R + G + B of an (H, W, 3 or 4) array in int64 (exact for 8 and 16 bits)."""
    return rgb[..., :3].astype(np.int64).sum(axis=-1)


@pytest.mark.parametrize("fmt", ["PNG", "TIFF"])
def test_pillow_rgb8_sum_and_channels(tmp_path, fmt):
    path = tmp_path / f"rgb.{fmt.lower()}"
    PILImage.fromarray(RGB8).save(path, format=fmt)
    total = read_image(path)
    assert total.colour and total.bit_depth == 8 and total.data.dtype == np.uint16
    np.testing.assert_array_equal(total.data, _rgb_sum(RGB8))
    assert total.data.max() > 255  # summed, not averaged or clipped to 8 bits
    for channel, index in (("r", 0), ("g", 1), ("b", 2)):
        picked = read_image(path, channel=channel)
        assert picked.data.dtype == np.uint8
        np.testing.assert_array_equal(picked.data, RGB8[..., index])


def test_rgba_png_ignores_alpha(tmp_path):
    alpha = RNG.integers(1, 256, size=RGB8.shape[:2]).astype(np.uint8)
    path = tmp_path / "rgba.png"
    PILImage.fromarray(np.dstack([RGB8, alpha])).save(path)
    image = read_image(path)
    assert image.colour and image.data.dtype == np.uint16
    np.testing.assert_array_equal(image.data, _rgb_sum(RGB8))
    np.testing.assert_array_equal(read_image(path, channel="b").data, RGB8[..., 2])


def test_grey_alpha_png_gives_grey(tmp_path):
    path = tmp_path / "la.png"
    PILImage.fromarray(np.dstack([GREY8, np.full_like(GREY8, 128)])).save(path)
    for channel in (None, "g"):
        image = read_image(path, channel=channel)
        assert not image.colour and image.data.dtype == np.uint8
        np.testing.assert_array_equal(image.data, GREY8)


def test_palette_png_is_colour(tmp_path):
    path = tmp_path / "palette.png"
    PILImage.fromarray(RGB8).convert("P").save(path)
    with PILImage.open(path) as pil:
        expected = np.asarray(pil.convert("RGB"))[..., 1]
    image = read_image(path, channel="g")
    assert image.colour
    np.testing.assert_array_equal(image.data, expected)


def test_jpeg_grey_and_exif(tmp_path):
    path = tmp_path / "exif.jpg"
    exif = PILImage.Exif()
    exif[0x0110] = "StarCam 1"  # Model
    exif.get_ifd(0x8769)[0x9003] = "2024:05:06 22:33:44"  # DateTimeOriginal
    exif.get_ifd(0x8769)[0x829A] = 0.25  # ExposureTime
    PILImage.fromarray(GREY8).save(path, quality=100, exif=exif)
    image = read_image(path)
    assert image.data.dtype == np.uint8 and image.bit_depth == 8 and not image.colour
    assert image.header["DateTimeOriginal"] == "2024:05:06 22:33:44"
    assert image.header["Model"] == "StarCam 1"
    assert image.header["ExposureTime"] == pytest.approx(0.25)
    # lossy, but quality 100 keeps values within a few DN
    assert np.max(np.abs(image.data.astype(int) - GREY8)) <= 8


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.uint16, np.int32, np.float32, np.float64])
def test_fits_native_dtype(tmp_path, dtype):
    array = (GREY16 // 2).astype(dtype)
    path = tmp_path / "image.fits"
    fits.writeto(path, array)
    image = read_image(path)
    assert image.data.dtype == np.dtype(dtype)
    assert image.data.dtype.isnative
    assert image.bit_depth == np.dtype(dtype).itemsize * 8
    np.testing.assert_array_equal(image.data, array)


def test_fits_bscale_bzero_applied(tmp_path):
    raw = GREY8.astype(np.int16)
    hdu = fits.PrimaryHDU(raw * 0.5 + 10.0)
    hdu.scale("int16", bscale=0.5, bzero=10.0)
    hdu.header["EXPTIME"] = (0.05, "seconds")
    path = tmp_path / "scaled.fits"
    hdu.writeto(path)
    assert fits.getheader(path)["BITPIX"] == 16  # stored as scaled integers
    image = read_image(path)
    assert image.data.dtype.kind == "f"
    np.testing.assert_allclose(image.data, raw * 0.5 + 10.0)
    assert image.header["EXPTIME"] == 0.05
    assert (image.header["BSCALE"], image.header["BZERO"]) == (0.5, 10.0)  # the file's cards
    assert image.bit_depth == 16


def test_fits_first_2d_hdu_and_colour_cube(tmp_path):
    path = tmp_path / "multi.fits"
    fits.HDUList([fits.PrimaryHDU(), fits.ImageHDU(np.zeros(5)),
                  fits.ImageHDU(np.moveaxis(RGB16, -1, 0), name="RGB"),
                  fits.ImageHDU(GREY16)]).writeto(path)
    image = read_image(path, channel="b")
    assert image.colour
    np.testing.assert_array_equal(image.data, RGB16[..., 2])
    assert image.header["EXTNAME"] == "RGB"


def test_fits_gzip(tmp_path):
    path = tmp_path / "image.fits.gz"
    fits.writeto(path, GREY16)
    np.testing.assert_array_equal(read_image(path).data, GREY16)


@pytest.mark.parametrize(("inner", "held"), [("png", "PNG"), ("txt", "something other than FITS")])
def test_a_gzip_file_of_something_else_than_fits_says_what_it_holds(tmp_path, inner, held):
    """Before: 'not a readable FITS file (Empty or corrupt FITS file)' for a gzipped PNG or JPEG."""
    import gzip

    source = tmp_path / f"image.{inner}"
    if inner == "png":
        PILImage.fromarray(GREY16.astype(np.uint8)).save(source)
    else:
        source.write_text("x,y\n1,2\n")
    path = tmp_path / f"image.{inner}.gz"
    path.write_bytes(gzip.compress(source.read_bytes()))
    with pytest.raises(ImageReadError, match=f"a gzip file holding {held}; only gzip-compressed FITS is read"):
        read_image(path)


# --- 16-bit colour TIFF, which Pillow would cut to 8 bits -------------------------------------
def _tiff_rgb16(array: np.ndarray, big_endian: bool, deflate: bool, predictor: bool) -> bytes:
    """A strip-based 16-bit RGB TIFF assembled here by hand, independently of startrack.io._tiff."""
    order = ">" if big_endian else "<"
    height, width, _ = array.shape
    samples = array.astype(np.int64)
    if predictor:  # horizontal differencing, modulo 2**16
        samples = np.concatenate([samples[:, :1], np.diff(samples, axis=1)], axis=1) % 65536
    rows = [samples[y].astype(order + "u2").tobytes() for y in range(height)]
    half = (height + 1) // 2  # rows per strip: two strips
    strips = [b"".join(rows[:half]), b"".join(rows[half:])]
    if deflate:
        strips = [zlib.compress(s) for s in strips]
    offsets = [8, 8 + len(strips[0])]
    bits_offset = 8 + len(strips[0]) + len(strips[1])
    ifd_offset = bits_offset + 6
    entries = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 3, bits_offset),
               (259, 3, 1, 8 if deflate else 1), (262, 3, 1, 2), (273, 4, 2, None),
               (277, 3, 1, 3), (278, 4, 1, half), (279, 4, 2, None), (284, 3, 1, 1),
               (317, 3, 1, 2 if predictor else 1)]
    longs_offset = ifd_offset + 2 + 12 * len(entries) + 4
    body = b""
    for tag, kind, count, value in entries:
        if tag == 273:
            field = struct.pack(order + "I", longs_offset)
        elif tag == 279:
            field = struct.pack(order + "I", longs_offset + 8)
        elif kind == 3 and count == 1:
            field = struct.pack(order + "HH", value, 0)
        else:
            field = struct.pack(order + "I", value)
        body += struct.pack(order + "HHI", tag, kind, count) + field
    head = (b"MM" if big_endian else b"II") + struct.pack(order + "HI", 42, ifd_offset)
    return (head + strips[0] + strips[1] + struct.pack(order + "3H", 16, 16, 16)
            + struct.pack(order + "H", len(entries)) + body + struct.pack(order + "I", 0)
            + struct.pack(order + "4I", offsets[0], offsets[1], len(strips[0]), len(strips[1])))


@pytest.mark.parametrize(("big_endian", "deflate", "predictor"),
                         [(False, False, False), (True, False, False), (False, True, False),
                          (True, True, True), (False, True, True)])
def test_tiff_rgb16_keeps_16_bits(tmp_path, big_endian, deflate, predictor):
    path = tmp_path / "rgb16.tif"
    path.write_bytes(_tiff_rgb16(RGB16, big_endian, deflate, predictor))
    with PILImage.open(path) as pil:  # the file is valid: Pillow reads it (high bytes only)
        np.testing.assert_array_equal(np.asarray(pil), (RGB16 >> 8).astype(np.uint8))
    for channel in range(3):
        image = read_image(path, channel=channel)
        assert image.data.dtype == np.uint16 and image.bit_depth == 16 and image.colour
        np.testing.assert_array_equal(image.data, RGB16[..., channel])
    total = read_image(path)
    assert total.data.dtype == np.uint32 and total.bit_depth == 16 and total.colour
    np.testing.assert_array_equal(total.data, _rgb_sum(RGB16))
    assert total.data.max() > 65535  # no uint16 overflow


# --- arrays ---------------------------------------------------------------------------------
def test_array_input():
    image = read_image(GREY16)
    assert image.path is None and image.header == {} and image.bit_depth == 16
    assert (image.width, image.height) == (23, 17)
    np.testing.assert_array_equal(image.data, GREY16)
    colour = read_image(RGB16, channel="r")
    assert colour.colour and colour.data.dtype == np.uint16
    np.testing.assert_array_equal(colour.data, RGB16[..., 0])
    total = read_image(RGB8)
    assert total.colour and total.bit_depth == 8 and total.data.dtype == np.uint16
    np.testing.assert_array_equal(total.data, _rgb_sum(RGB8))
    rgba = read_image(np.dstack([RGB16, GREY16]))
    assert rgba.colour and rgba.data.dtype == np.uint32
    np.testing.assert_array_equal(rgba.data, _rgb_sum(RGB16))
    single = read_image(GREY8[..., None])
    assert not single.colour and single.data.dtype == np.uint8
    np.testing.assert_array_equal(single.data, GREY8)
    grey_alpha = read_image(np.dstack([GREY16, RGB16[..., 0]]), channel="r")
    assert not grey_alpha.colour and grey_alpha.data.dtype == np.uint16
    np.testing.assert_array_equal(grey_alpha.data, GREY16)


# --- real files ------------------------------------------------------------------------------
def test_real_images_match_truth_sizes(realdata_dir, truth_table):
    """The 8-bit colour PNGs (RGBA) and JPEGs (RGB) become uint16 R + G + B, as Pillow decodes."""
    for row in truth_table:
        path = realdata_dir / row["set"] / row["file"]
        image = read_image(path)
        assert image.data.shape == (int(row["height"]), int(row["width"])), row["file"]
        assert image.bit_depth == 8 and image.colour
        assert image.data.dtype == np.uint16
        with PILImage.open(path) as pil:
            pixels = np.asarray(pil)
        np.testing.assert_array_equal(image.data, _rgb_sum(pixels), err_msg=row["file"])
        green = read_image(path, channel="g")
        assert green.data.dtype == np.uint8
        np.testing.assert_array_equal(green.data, pixels[..., 1], err_msg=row["file"])
