"""Bad input: every unreadable file raises ImageReadError naming the file and the problem."""

from __future__ import annotations

import io

import numpy as np
import pytest
from astropy.io import fits
from PIL import Image as PILImage
from PIL import ImageFile

from startrack.errors import ImageReadError, InvalidInputError
from startrack.io import read_image, write_tiff
from startrack.io._tiff import read_tiff16_colour

RNG = np.random.default_rng(7)
NOISE = RNG.integers(0, 256, size=(120, 160, 3)).astype(np.uint8)


def _save(tmp_path, name, fmt, array=NOISE, **kwargs):
    path = tmp_path / name
    PILImage.fromarray(array).save(path, format=fmt, **kwargs)
    return path


def _truncate(path, fraction):
    data = path.read_bytes()
    out = path.with_name("cut-" + path.name)
    out.write_bytes(data[: int(len(data) * fraction)])
    return out


def _expect(path, match):
    with pytest.raises(ImageReadError, match=match) as info:
        read_image(path)
    assert str(path) in str(info.value)
    assert isinstance(info.value, ValueError)


def test_missing_file(tmp_path):
    _expect(tmp_path / "absent.png", "does not exist")


def test_folder_is_not_an_image(tmp_path):
    _expect(tmp_path, "not a regular file")


def test_empty_file(tmp_path):
    path = tmp_path / "empty.fits"
    path.write_bytes(b"")
    _expect(path, r"empty \(0 bytes\)")


def test_text_file(tmp_path):
    path = tmp_path / "notes.png"
    path.write_text("this is not an image\n")
    _expect(path, "not an image file")


@pytest.mark.parametrize(("fmt", "name"), [("GIF", "image.gif"), ("ICO", "image.ico")])
def test_unsupported_formats(tmp_path, fmt, name):
    _expect(_save(tmp_path, name, fmt), f"unsupported image format {fmt}")


@pytest.mark.parametrize("fraction", [0.02, 0.5, 0.9, 0.995])
@pytest.mark.parametrize(("fmt", "name"), [("PNG", "image.png"), ("JPEG", "image.jpg")])
def test_truncated_png_and_jpeg(tmp_path, fmt, name, fraction):
    _expect(_truncate(_save(tmp_path, name, fmt), fraction), "truncated or corrupt")


def test_truncated_raises_even_if_pillow_is_told_to_accept_it(tmp_path, monkeypatch):
    monkeypatch.setattr(ImageFile, "LOAD_TRUNCATED_IMAGES", True)
    cut = _truncate(_save(tmp_path, "image.png", "PNG"), 0.5)
    _expect(cut, "truncated")
    assert ImageFile.LOAD_TRUNCATED_IMAGES is True  # the global setting is restored


@pytest.mark.parametrize("fraction", [0.3, 0.6])
def test_truncated_tiff(tmp_path, fraction):
    _expect(_truncate(_save(tmp_path, "image.tif", "TIFF"), fraction), "truncated")


def test_truncated_rgb16_tiff(tmp_path):
    path = tmp_path / "rgb16.tif"
    write_tiff(path, NOISE.astype(np.uint16) * 257)
    with PILImage.open(path) as pil:
        tags = dict(pil.tag_v2)
    raw = path.read_bytes()
    for cut in (raw[: len(raw) // 2], raw[:100]):  # the strip runs past the end of the data
        with pytest.raises(ImageReadError, match=r"rgb16.tif: TIFF file is truncated"):
            read_tiff16_colour(path, io.BytesIO(cut), tags)


def test_corrupt_tiff_directory(tmp_path):
    path = tmp_path / "rgb16.tif"
    write_tiff(path, NOISE.astype(np.uint16) * 257)
    raw = path.read_bytes()
    cut = tmp_path / "cut.tif"
    cut.write_bytes(raw[: len(raw) - 40])  # directory (stored after the pixels) cut short
    _expect(cut, "truncated or corrupt")


@pytest.mark.parametrize("keep_bytes", [1000, 2880, 2880 + 5000, -1])
def test_truncated_fits(tmp_path, keep_bytes):
    path = tmp_path / "image.fits"
    fits.writeto(path, RNG.random((60, 60)))
    cut = tmp_path / "cut.fits"
    cut.write_bytes(path.read_bytes()[:keep_bytes])
    _expect(cut, "truncated|not a readable FITS")


def test_fits_without_image(tmp_path):
    path = tmp_path / "table.fits"
    fits.HDUList([fits.PrimaryHDU(), fits.BinTableHDU.from_columns(
        [fits.Column(name="x", format="D", array=np.arange(3.0))])]).writeto(path)
    _expect(path, "no 2-D image")


def test_real_truncated_png(realdata_dir):
    """median_image.png in the shared real data stops after 64 KiB, inside its image data."""
    path = realdata_dir / "UBNanosatLab-openstartracker" / "median_image.png"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    _expect(path, "truncated")


# --- misuse ----------------------------------------------------------------------------------
@pytest.mark.parametrize("shape", [(10,), (4, 4, 0), (4, 4, 5), (2, 4, 4, 3), (0, 5)])
def test_bad_array_shapes(shape):
    with pytest.raises(InvalidInputError, match="shape"):
        read_image(np.zeros(shape))


@pytest.mark.parametrize("array", [np.zeros((3, 3), bool), np.zeros((3, 3), complex),
                                   np.array([["a"]])])
def test_bad_array_dtypes(array):
    with pytest.raises(InvalidInputError, match="dtype"):
        read_image(array)


def test_bad_source_type():
    with pytest.raises(InvalidInputError, match="path or a numpy array"):
        read_image([[1, 2], [3, 4]])


@pytest.mark.parametrize("channel", ["alpha", "a", 3, -1, 1.5, True])
@pytest.mark.parametrize("shape", [(3, 3), (3, 3, 1), (3, 3, 2), (3, 3, 3), (3, 3, 4)])
def test_bad_channel_even_for_grey(shape, channel):
    with pytest.raises(InvalidInputError, match="channel"):
        read_image(np.zeros(shape), channel=channel)


@pytest.mark.parametrize("channel", ["alpha", 3])
def test_bad_channel_is_refused_before_the_file_is_read(tmp_path, channel):
    for path in (_save(tmp_path, "image.png", "PNG"), tmp_path / "absent.png"):
        with pytest.raises(InvalidInputError, match="channel"):
            read_image(path, channel=channel)


def test_size_limit_replaces_pillows_and_can_be_raised(tmp_path, monkeypatch):
    """Pillow's own limit (MAX_IMAGE_PIXELS) no longer decides; ours does, for every format."""
    monkeypatch.setattr(PILImage, "MAX_IMAGE_PIXELS", 100)
    path = _save(tmp_path, "big.png", "PNG")
    assert read_image(path).data.shape == NOISE.shape[:2]
    with pytest.raises(ImageReadError, match=r"over the limit of 100 px.*--max-pixels"):
        read_image(path, max_pixels=100)
    assert PILImage.MAX_IMAGE_PIXELS == 100
