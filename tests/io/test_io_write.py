"""Writers: lossless by dtype, explicit refusals, atomic replacement."""

from __future__ import annotations

import os

import numpy as np
import pytest
from astropy.io import fits
from PIL import Image as PILImage

from startrack.errors import InvalidInputError
from startrack.io import read_image, write_fits, write_png, write_tiff

RNG = np.random.default_rng(99)
GREY8 = RNG.integers(0, 256, size=(13, 11)).astype(np.uint8)
GREY16 = RNG.integers(0, 65536, size=(13, 11)).astype(np.uint16)
RGB8 = RNG.integers(0, 256, size=(13, 11, 3)).astype(np.uint8)
RGB16 = RNG.integers(0, 65536, size=(13, 11, 3)).astype(np.uint16)
FLOAT32 = RNG.normal(100.0, 10.0, size=(13, 11)).astype(np.float32)


def _pillow_read(path):
    with PILImage.open(path) as pil:
        return pil.mode, np.asarray(pil)


@pytest.mark.parametrize(("array", "mode"), [(GREY8, "L"), (GREY16, "I;16"), (RGB8, "RGB")])
def test_png_is_lossless_and_read_by_pillow(tmp_path, array, mode):
    path = write_png(tmp_path / "out.png", array)
    pil_mode, pixels = _pillow_read(path)
    assert pil_mode == mode
    np.testing.assert_array_equal(pixels, array)


def test_png_big_endian_input(tmp_path):
    path = write_png(tmp_path / "be.png", GREY16.astype(">u2"))
    np.testing.assert_array_equal(read_image(path).data, GREY16)


@pytest.mark.parametrize(("array", "match"), [
    (FLOAT32, "float.*convert explicitly"),
    (GREY16.astype(np.float64), "float"),
    (GREY16.astype(np.int16), "uint8 or uint16"),
    (GREY8.astype(bool), "uint8 or uint16"),
    (RGB16, "uint8 or uint16"),
    (np.zeros((0, 4), np.uint8), "non-empty"),
])
def test_png_refusals(tmp_path, array, match):
    with pytest.raises(InvalidInputError, match=match):
        write_png(tmp_path / "out.png", array)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("array", "mode"),
                         [(GREY8, "L"), (GREY16, "I;16"), (FLOAT32, "F"), (RGB8, "RGB")])
def test_tiff_is_read_by_pillow(tmp_path, array, mode):
    path = write_tiff(tmp_path / "out.tif", array)
    pil_mode, pixels = _pillow_read(path)
    assert pil_mode == mode
    np.testing.assert_array_equal(pixels, array)
    np.testing.assert_array_equal(read_image(path, channel="g").data,
                                  array[..., 1] if array.ndim == 3 else array)


def test_tiff_rgb16_round_trip(tmp_path):
    path = write_tiff(tmp_path / "rgb16.tif", RGB16)
    _, high_bytes = _pillow_read(path)  # Pillow itself keeps only the high byte
    np.testing.assert_array_equal(high_bytes, RGB16 >> 8)
    for channel in range(3):
        np.testing.assert_array_equal(read_image(path, channel=channel).data, RGB16[..., channel])


@pytest.mark.parametrize("array", [GREY16.astype(np.float64), GREY16.astype(np.int16),
                                   RGB8.astype(np.float32), np.zeros((4, 4, 2), np.uint8)])
def test_tiff_refusals(tmp_path, array):
    with pytest.raises(InvalidInputError, match="TIFF image"):
        write_tiff(tmp_path / "out.tif", array)


# --- FITS ------------------------------------------------------------------------------------
def test_fits_header_and_tables(tmp_path):
    truth = {"x": np.array([1.5, 2.5]), "y": np.array([3.0, 4.0]), "id": np.array([7, 9])}
    header = {"EXPTIME": (0.05, "exposure [s]"), "CAMERA": "far-mst", "HISTORY": ["a", "b"],
              "LONG_KEYWORD": 3}
    path = write_fits(tmp_path / "sim.fits", GREY16, header=header, tables={"truth": truth})
    with fits.open(path) as hdus:
        assert hdus[0].header["EXPTIME"] == 0.05
        assert hdus[0].header.comments["EXPTIME"] == "exposure [s]"
        assert hdus[0].header["LONG_KEYWORD"] == 3
        assert list(hdus[0].header["HISTORY"]) == ["a", "b"]
        table = hdus["TRUTH"].data
        np.testing.assert_array_equal(table["x"], truth["x"])
        np.testing.assert_array_equal(table["id"], truth["id"])
        assert hdus[0].data.dtype == np.uint16
    image = read_image(path)
    np.testing.assert_array_equal(image.data, GREY16)
    assert image.header["CAMERA"] == "far-mst"


def test_fits_structural_cards_of_another_image_are_dropped(tmp_path):
    """A header read from a uint16 file (BZERO 32768) must not rescale float data written later."""
    source = write_fits(tmp_path / "u16.fits", GREY16, header={"OBJECT": "M45"})
    header = read_image(source).header
    assert header["BZERO"] == 32768
    out = write_fits(tmp_path / "f32.fits", FLOAT32, header=header)
    image = read_image(out)
    assert image.data.dtype == np.float32 and image.header["OBJECT"] == "M45"
    np.testing.assert_array_equal(image.data, FLOAT32)


def test_fits_accepts_astropy_header(tmp_path):
    header = fits.Header()
    header["DATE-OBS"] = "2024-01-01T00:00:00"
    header.add_comment("simulated")
    path = write_fits(tmp_path / "h.fits", GREY8, header=header)
    got = read_image(path).header
    assert got["DATE-OBS"] == "2024-01-01T00:00:00" and got["COMMENT"] == ["simulated"]


@pytest.mark.parametrize("array", [RGB8, GREY8.astype(bool), np.zeros((0, 3))])
def test_fits_refuses_non_2d_or_non_numeric(tmp_path, array):
    with pytest.raises(InvalidInputError, match="FITS image"):
        write_fits(tmp_path / "x.fits", array)


def test_fits_bad_table(tmp_path):
    with pytest.raises(InvalidInputError, match="table 'truth'"):
        write_fits(tmp_path / "x.fits", GREY8, tables={"truth": {"x": [1, 2], "y": [1, 2, 3]}})


# --- atomicity (the failure cases are in test_io_outputs.py) ---------------------------------
def test_overwrite_and_permissions(tmp_path):
    target = tmp_path / "image.tif"
    write_tiff(target, GREY8)
    write_tiff(target, GREY16)
    np.testing.assert_array_equal(read_image(target).data, GREY16)
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask
    assert [p.name for p in tmp_path.iterdir()] == ["image.tif"]


def test_missing_folder(tmp_path):
    for writer in (write_png, write_tiff, write_fits):
        with pytest.raises(InvalidInputError, match="does not exist"):
            writer(tmp_path / "no" / "image", GREY8)
