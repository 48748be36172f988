"""Every input bounded (docs/io.md, "Limits"): sizes checked from the header before anything is
decoded, files read no further than needed, text bounded, broken metadata ignored, huge values
and masked pixels handled. Each test names what happened before."""

from __future__ import annotations

import gzip
import io
import struct
import subprocess
import sys
import zlib

import numpy as np
import pytest
from astropy.io import fits
from PIL import Image as PILImage

from startrack.errors import ImageReadError, InvalidInputError
from startrack.io import read_image, read_star_list
from startrack.io._fitsfile import MAX_HEADER_BLOCKS
from startrack.io._limits import DEFAULT_MAX_PIXELS, ENV_VAR, max_pixels_limit
from startrack.io._starlist import MAX_LINE_CHARS


def _fits_header_only(width: int, height: int, bitpix: int) -> bytes:
    cards = [f"SIMPLE  = {'T':>20}", f"BITPIX  = {bitpix:>20}", f"NAXIS   = {2:>20}",
             f"NAXIS1  = {width:>20}", f"NAXIS2  = {height:>20}", "END"]
    return "".join(card.ljust(80) for card in cards).ljust(2880).encode("ascii")


def test_a_fits_header_claiming_10_gigapixels_is_refused_from_its_header(tmp_path):
    """Before: a 2,880-byte file claiming 100,000 x 100,000 px ended in a MemoryError (exit 1)."""
    path = tmp_path / "claims.fits"
    path.write_bytes(_fits_header_only(100_000, 100_000, 16))
    with pytest.raises(ImageReadError, match=r"100000 x 100000 = 10,000,000,000 px, over the limit"):
        read_image(path)


def test_a_small_gzip_fits_of_a_huge_image_is_refused_before_decompression(tmp_path):
    """Before: a 1.5 MB gzip FITS took 59 s and 3.2 GB to be read."""
    path = tmp_path / "bomb.fits.gz"
    with gzip.open(path, "wb") as fh:
        fh.write(_fits_header_only(20_000, 20_000, -64))
        fh.write(bytes(8 << 20))  # the first 8 MB of 3.2 GB of zeros
    assert path.stat().st_size < 100_000
    with pytest.raises(ImageReadError, match="400,000,000 px, over the limit"):
        read_image(path)


def test_a_fits_header_without_end_is_refused_after_a_bounded_read(tmp_path):
    card = "COMMENT " + "x" * 72
    path = tmp_path / "endless.fits"
    path.write_bytes(("SIMPLE  = " + "T".rjust(20)).ljust(80).encode() + (card * (36 * MAX_HEADER_BLOCKS)).encode())
    with pytest.raises(ImageReadError, match="no END card"):
        read_image(path)


def test_a_fits_image_with_values_near_1e300_is_refused_with_a_message(tmp_path):
    """Before: detection printed 'RuntimeWarning: overflow encountered in cast' and then said the
    image had no finite pixel."""
    path = tmp_path / "huge_values.fits"
    fits.PrimaryHDU(np.full((16, 16), 1e300)).writeto(path)
    with pytest.raises(ImageReadError, match=r"pixel values reach 1e\+300"):
        read_image(path)
    read_image(np.full((4, 4), 1e29))


def _png_claiming(width: int, height: int) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(bytes(1000))) + chunk(b"IEND", b""))


def test_one_limit_for_every_format_raised_by_the_environment(tmp_path, monkeypatch):
    """Before: a genuine 20,000 x 20,000 PNG was refused by Pillow's bomb check with no way to
    allow it from startrack, while FITS had no limit at all."""
    path = tmp_path / "claims.png"
    path.write_bytes(_png_claiming(20_000, 20_000))
    with pytest.raises(ImageReadError, match="400,000,000 px, over the limit of 100,000,000"):
        read_image(path)
    small = tmp_path / "small.png"
    PILImage.fromarray(np.zeros((30, 40), np.uint8)).save(small)
    monkeypatch.setenv(ENV_VAR, "1000")
    with pytest.raises(ImageReadError, match="over the limit of 1,000 px"):
        read_image(small)
    with max_pixels_limit(2000):
        assert read_image(small).data.shape == (30, 40)
    assert read_image(small, max_pixels=DEFAULT_MAX_PIXELS).data.shape == (30, 40)
    monkeypatch.setenv(ENV_VAR, "lots")
    with pytest.raises(InvalidInputError, match=ENV_VAR):
        read_image(small)


def _tiff16_rgb_with_strip(width: int, height: int, strip: bytes) -> bytes:
    """A little-endian 16-bit RGB TIFF with one Deflate strip (TIFF 6.0 tags)."""
    entries = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 3, None), (259, 3, 1, 8), (262, 3, 1, 2),
               (273, 4, 1, None), (277, 3, 1, 3), (278, 4, 1, height), (279, 4, 1, len(strip)), (284, 3, 1, 1)]
    ifd_size = 2 + 12 * len(entries) + 4
    bits_at, strip_at = 8 + ifd_size, 8 + ifd_size + 6
    ifd = struct.pack("<H", len(entries))
    for tag, kind, count, value in entries:
        value = {258: bits_at, 273: strip_at}.get(tag, value)
        packed = struct.pack("<H", value) + b"\0\0" if kind == 3 and count == 1 else struct.pack("<I", value)
        ifd += struct.pack("<HHI", tag, kind, count) + packed
    return b"II*\x00" + struct.pack("<I", 8) + ifd + struct.pack("<I", 0) + struct.pack("<3H", 16, 16, 16) + strip


def test_a_tiff_strip_that_inflates_past_the_image_is_refused(tmp_path):
    """Before: a 1 MB TIFF whose strip inflated to 1 GiB took 2.2 GB and was accepted."""
    path = tmp_path / "bomb.tif"
    path.write_bytes(_tiff16_rgb_with_strip(16, 16, zlib.compress(bytes(64 << 20), 9)))
    assert path.stat().st_size < 200_000
    with pytest.raises(ImageReadError, match="inflates past the image's size"):
        read_image(path)
    good = tmp_path / "good.tif"
    pixels = np.arange(16 * 16 * 3, dtype="<u2").reshape(16, 16, 3)
    good.write_bytes(_tiff16_rgb_with_strip(16, 16, zlib.compress(pixels.tobytes())))
    np.testing.assert_array_equal(read_image(good, channel="g").data, pixels[..., 1])


def test_a_sparse_3_gib_file_is_not_read_whole(tmp_path):
    """Before: the whole file was read to say 'not an image' (3 GiB of memory). The reader runs in a
    process whose address space is capped at 2 GiB, so reading the file whole fails there."""
    path = tmp_path / "sparse.bin"
    with open(path, "wb") as fh:
        fh.truncate(3 << 30)
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))\n"
            "from startrack.io import read_image\n"
            "try:\n    read_image(sys.argv[1])\nexcept Exception as exc:\n    print(type(exc).__name__, exc)\n")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=120)
    assert out.stdout.startswith("ImageReadError") and "not an image file" in out.stdout, out.stdout + out.stderr


def _jpeg_with_broken_exif() -> bytes:
    buffer = io.BytesIO()
    PILImage.fromarray((np.arange(64 * 64) % 251).astype(np.uint8).reshape(64, 64)).save(buffer, "JPEG")
    # an EXIF IFD whose XResolution points 5,000 bytes past the end of the block
    tiff = b"II*\x00" + struct.pack("<IH", 8, 1) + struct.pack("<HHI4s", 0x011A, 5, 1, struct.pack("<I", 5000))
    payload = b"Exif\x00\x00" + tiff + b"\0\0\0\0"
    jpeg = buffer.getvalue()
    return jpeg[:2] + b"\xff\xe1" + struct.pack(">H", len(payload) + 2) + payload + jpeg[2:]


def test_a_jpeg_with_broken_exif_is_read_without_it(tmp_path):
    """Before: refused as 'image header is truncated or corrupt (Truncated File Read)', though the
    reader documents that unparsable EXIF is left out."""
    path = tmp_path / "broken_exif.jpg"
    path.write_bytes(_jpeg_with_broken_exif())
    image = read_image(path)
    assert image.data.shape == (64, 64) and "XResolution" not in image.header


def test_a_truncated_jpeg_is_still_refused(tmp_path):
    path = tmp_path / "cut.jpg"
    path.write_bytes(_jpeg_with_broken_exif()[:-300])
    with pytest.raises(ImageReadError, match="truncated or corrupt"):
        read_image(path)


def test_a_star_list_field_over_131072_characters_is_refused_with_a_line_number(tmp_path):
    """Before: ``_csv.Error: field larger than field limit (131072)`` and a traceback."""
    path = tmp_path / "stars.csv"
    path.write_text("x,y\n1.5," + "9" * 200_000 + "\n")
    with pytest.raises(InvalidInputError, match=f"line 2: longer than {MAX_LINE_CHARS} characters"):
        read_star_list(path)
    quoted = tmp_path / "quoted.csv"
    quoted.write_text('x,y\n"1.5\n2",3\n')
    with pytest.raises(InvalidInputError, match="runs over several lines"):
        read_star_list(quoted)


def test_masked_pixels_become_nan():
    """Before: the mask was dropped and masked pixels were used as data."""
    data = np.ma.masked_array(np.full((4, 5), 100, np.uint16), mask=np.zeros((4, 5), bool))
    data.mask[1, 2] = True
    image = read_image(data)
    assert np.isnan(image.data[1, 2]) and np.isfinite(image.data).sum() == 19
    assert image.data.dtype == np.float32
