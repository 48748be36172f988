"""The direct read of plain FITS images gives what astropy gives, and leaves the rest to astropy."""

from __future__ import annotations

import gzip

import numpy as np
import pytest
from astropy.io import fits

from startrack.errors import ImageReadError
from startrack.io import read_image
from startrack.io._fits_plain import read_plain_fits

RNG = np.random.default_rng(7)
PLAIN = {
    "uint16": RNG.integers(0, 65536, (37, 53)).astype(np.uint16),
    "int16": RNG.integers(-32768, 32768, (20, 31)).astype(np.int16),
    "uint8": RNG.integers(0, 256, (16, 9)).astype(np.uint8),
}


def _write(path, data, **cards):
    fits.PrimaryHDU(data, header=fits.Header(list(cards.items()))).writeto(path)
    return path


def _astropy(path):
    with fits.open(path) as hdus:
        return np.array(hdus[0].data), hdus[0].header


@pytest.mark.parametrize("kind", sorted(PLAIN))
def test_plain_images_read_directly_equal_astropy(tmp_path, kind):
    path = _write(tmp_path / f"{kind}.fits", PLAIN[kind], EXPTIME=0.25, OBJECT="field")
    direct = read_plain_fits(path, None, 100)
    assert direct is not None
    data, header = direct
    ref, ref_header = _astropy(path)
    assert data.dtype == ref.dtype.newbyteorder("=") and data.dtype.isnative
    np.testing.assert_array_equal(data, ref)
    assert data.flags.writeable  # in memory, not a map of the file
    assert dict(header) == dict(ref_header)
    image = read_image(path)
    np.testing.assert_array_equal(image.data, PLAIN[kind])
    assert image.header["EXPTIME"] == 0.25


@pytest.mark.parametrize("make", ["float32", "bscale", "blank", "cube", "extension", "gzip"])
def test_other_layouts_are_left_to_astropy(tmp_path, make):
    path = tmp_path / "x.fits"
    data = PLAIN["int16"]
    if make == "float32":
        _write(path, data.astype(np.float32))
    elif make == "bscale":
        hdu = fits.PrimaryHDU(data)
        hdu.scale("int16", bscale=2.0, bzero=0.0)
        hdu.writeto(path)
    elif make == "blank":
        _write(path, data, BLANK=-32768)
    elif make == "cube":
        _write(path, np.stack([data] * 3))
    elif make == "extension":
        fits.HDUList([fits.PrimaryHDU(), fits.ImageHDU(data)]).writeto(path)
    else:
        plain = _write(tmp_path / "plain.fits", data)
        path.write_bytes(gzip.compress(plain.read_bytes()))
    assert read_plain_fits(path, None, 100) is None
    assert read_image(path).data.shape[:2] == data.shape  # astropy still reads it


def test_a_truncated_plain_file_is_refused_by_the_astropy_path(tmp_path):
    path = _write(tmp_path / "t.fits", PLAIN["uint16"])
    path.write_bytes(path.read_bytes()[:-2880])
    assert read_plain_fits(path, None, 100) is None
    with pytest.raises(ImageReadError, match="truncated"):
        read_image(path)


def test_a_header_with_a_text_size_is_refused_naming_the_card(tmp_path):
    cards = ["SIMPLE  =                    T", "BITPIX  =                   16", "NAXIS   =                    2",
             "NAXIS1  = 'abc'", "NAXIS2  =                    4", "END"]
    path = tmp_path / "odd.fits"
    path.write_bytes("".join(c.ljust(80) for c in cards).ljust(2880).encode() + bytes(2880))
    for read in (lambda: read_plain_fits(path, None, 100), lambda: read_image(path)):
        with pytest.raises(ImageReadError, match="card NAXIS1 is 'abc'"):
            read()
