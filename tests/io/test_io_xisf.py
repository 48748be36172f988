"""XISF images (:mod:`startrack.io._xisf`): every layout, codec and location of the specification
read to the same pixels, the FITS keywords and XISF properties carried over, damaged and
unsupported files refused with a message, and a star frame solved from an XISF file.

The files are written here by :func:`write_xisf`, from the specification (XISF 1.0): no XISF
writer is a dependency of the project."""

from __future__ import annotations

import base64
import hashlib
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.camera import Camera
from startrack.errors import ImageReadError
from startrack.frames import attitude_error
from startrack.io import IMAGE_SUFFIXES, read_image
from startrack.io._xisf import keyword_value, read_xisf
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.solve import solve_image
from startrack.units import ARCSEC

SAMPLE_FORMATS = {np.dtype("uint8"): "UInt8", np.dtype("uint16"): "UInt16", np.dtype("uint32"): "UInt32",
                  np.dtype("float32"): "Float32", np.dtype("float64"): "Float64"}


def _compressed(block: bytes, codec: str, item: int) -> tuple[bytes, str]:
    """``block`` compressed with ``codec`` (``+sh``: shuffled by ``item`` bytes first; ``zlib/2``:
    in two sub-blocks)."""
    name = codec.removesuffix("+sh")
    if codec.endswith("+sh"):
        count = len(block) // item
        block = np.frombuffer(block, np.uint8, count * item).reshape(count, item).T.tobytes() + block[count * item:]
    if name == "zlib/2":
        halves = [block[: len(block) // 2], block[len(block) // 2:]]
        packed = [zlib.compress(half) for half in halves]
        pairs = ":".join(f"{len(p)},{len(h)}" for p, h in zip(packed, halves, strict=True))
        return b"".join(packed), f' compression="zlib:{len(block)}" subblocks="{pairs}"'
    if name == "zlib":
        packed = zlib.compress(block)
    elif name.startswith("lz4"):
        packed = pytest.importorskip("lz4.block").compress(block, store_size=False)
    else:
        packed = pytest.importorskip("zstandard").ZstdCompressor().compress(block)
    size = len(block) if not codec.endswith("+sh") else f"{len(block)}:{item}"
    return packed, f' compression="{codec}:{size}"'


def write_xisf(path: Path, pixels: np.ndarray, *, storage: str = "Planar", codec: str | None = None,
               location: str = "attachment", big_endian: bool = False, checksum: bool = False,
               inside: str = "") -> None:
    """A monolithic XISF 1.0 file of one image (H, W) or (H, W, C); ``inside``: XML placed in the
    Image element (FITS keywords, properties, a colour filter array)."""
    cube = pixels[..., None] if pixels.ndim == 2 else pixels
    height, width, channels = cube.shape
    ordered = cube.transpose(2, 0, 1) if storage == "Planar" else cube
    block = ordered.astype(ordered.dtype.newbyteorder(">" if big_endian else "<")).tobytes()
    attributes = ""
    if codec:
        block, attributes = _compressed(block, codec, pixels.dtype.itemsize)
    if checksum:
        attributes += f' checksum="sha-1:{hashlib.sha1(block).hexdigest()}"'
    attributes += ' byteOrder="big"' if big_endian else ""
    body = ""
    if location == "inline":
        body = base64.b64encode(block).decode()
    elif location == "embedded":
        body = f'<Data encoding="base64">{base64.b64encode(block).decode()}</Data>'
    position = 0
    for _ in range(5):  # the header's length depends on the position it names: settle it
        where = {"attachment": f"attachment:{position}:{len(block)}", "inline": "inline:base64",
                 "embedded": "embedded"}[location]
        header = (f'<?xml version="1.0" encoding="UTF-8"?><xisf version="1.0" xmlns="http://www.pixinsight.com/xisf">'
                  f'<Image geometry="{width}:{height}:{channels}" sampleFormat="{SAMPLE_FORMATS[pixels.dtype]}" '
                  f'colorSpace="{"Gray" if channels == 1 else "RGB"}" pixelStorage="{storage}" location="{where}"'
                  f'{attributes}>{inside}{body}</Image></xisf>').encode()
        position = 16 + len(header)
    tail = block if location == "attachment" else b""
    path.write_bytes(b"XISF0100" + struct.pack("<II", len(header), 0) + header + tail)


@pytest.fixture(scope="module")
def rgb16() -> np.ndarray:
    return (np.arange(24 * 40 * 3, dtype=np.uint32).reshape(24, 40, 3) * 37 % 65536).astype(np.uint16)


@pytest.mark.parametrize("storage", ["Planar", "Normal"])
@pytest.mark.parametrize("codec", [None, "zlib", "zlib+sh", "zlib/2", "lz4", "lz4hc+sh", "zstd", "zstd+sh"])
def test_every_codec_and_storage_reads_the_same_pixels(tmp_path, rgb16, storage, codec):
    write_xisf(tmp_path / "a.xisf", rgb16, storage=storage, codec=codec, checksum=True)
    data, _, bits = read_xisf(tmp_path / "a.xisf")
    np.testing.assert_array_equal(data, rgb16)
    assert bits == 16


@pytest.mark.parametrize("location", ["inline", "embedded"])
@pytest.mark.parametrize("dtype", ["uint8", "uint32", "float32", "float64"])
def test_every_location_sample_format_and_byte_order_reads(tmp_path, location, dtype):
    grey = (np.arange(15 * 9).reshape(15, 9) * 3).astype(dtype)
    for big in (False, True):
        write_xisf(tmp_path / "g.xisf", grey, location=location, big_endian=big)
        data, _, bits = read_xisf(tmp_path / "g.xisf")
        assert data.shape == (15, 9) and bits == np.dtype(dtype).itemsize * 8
        np.testing.assert_array_equal(data, grey)


def test_keywords_time_and_bayer_pattern_come_with_the_pixels(tmp_path):
    inside = ('<FITSKeyword name="EXPTIME" value="30." comment=""/><FITSKeyword name="OBJECT" value="\'M 42\'"/>'
              '<FITSKeyword name="GAIN" value="120"/><FITSKeyword name="COMMENT" value="" comment="taken by N.I.N.A."/>'
              '<Property id="Observation:Time:Start" type="TimePoint" value="2024-01-05T22:10:00.5+01:00"/>'
              '<ColorFilterArray pattern="RGGB" width="2" height="2"/><FITSKeyword name="BAYERPAT" value="\'GRBG\'"/>')
    mosaic = np.full((32, 48), 1000, np.uint16)
    write_xisf(tmp_path / "m.xisf", mosaic, inside=inside)
    image = read_image(tmp_path / "m.xisf")
    assert image.header["EXPTIME"] == 30.0 and image.header["OBJECT"] == "M 42" and image.header["GAIN"] == 120
    assert image.header["COMMENT"] == ["taken by N.I.N.A."]
    assert image.header["DATE-OBS"] == "2024-01-05T21:10:00.500000"  # UTC
    assert image.header["BAYERPAT"] == "GRBG" and image.mosaic == "GRBG"  # the keyword, where there is one
    write_xisf(tmp_path / "cfa.xisf", mosaic, inside='<ColorFilterArray pattern="BGGR" width="2" height="2"/>')
    assert read_image(tmp_path / "cfa.xisf").mosaic == "BGGR"
    assert ".xisf" in IMAGE_SUFFIXES


@pytest.mark.parametrize(("text", "value"), [("'a ''b'' c  '", "a 'b' c"), ("T", True), ("F", False), ("-12", -12),
                                             ("1.5D3", 1500.0), ("", None), ("NAN?", "NAN?")])
def test_keyword_values_are_read_as_fits_cards_write_them(text, value):
    assert keyword_value(text) == value


EDITS = {"codec": (b'compression="zlib:', b'compression="lzma:'),
         "geometry": (b'geometry="40:24:3"', b'geometry="40:24:2:3"'),
         "complex": (b'sampleFormat="UInt16"', b'sampleFormat="Complex32"'), "xml": (b"</xisf>", b"</xisg>"),
         "declared": (b'compression="zlib:5760"', b'compression="zlib:9999999"'),
         "channels": (b'geometry="40:24:3"', b'geometry="40:24:5"')}
"""Header edits of :func:`_damaged`: the text replaced and its replacement."""


def _damaged(path: Path, rgb16: np.ndarray, how: str) -> None:
    codec = "zlib" if how in ("codec", "checksum", "declared") else None
    write_xisf(path, rgb16, codec=codec, checksum=how == "checksum")
    raw = path.read_bytes()
    if how == "truncated":
        path.write_bytes(raw[:-100])
    elif how == "checksum":
        path.write_bytes(raw[:-1] + bytes([raw[-1] ^ 0xFF]))
    else:  # the header edited and its length written anew (a codec of the same length: the block stays put)
        (length,) = struct.unpack("<I", raw[8:12])
        header = raw[16:16 + length].replace(*EDITS[how])
        path.write_bytes(raw[:8] + struct.pack("<II", len(header), 0) + header + raw[16 + length:])


@pytest.mark.parametrize(("how", "words"), [("truncated", "truncated XISF file"), ("checksum", "checksum"),
                                            ("codec", "codec 'lzma' is not read"),
                                            ("geometry", "more than two dimensions"),
                                            ("complex", "sample format 'Complex32'"), ("xml", "not well-formed"),
                                            ("declared", "declares 9,999,999 bytes; the image's geometry needs 5,760"),
                                            ("channels", "5 channels; 1 \\(grey\\) to 4")])
def test_damaged_or_unsupported_files_are_refused_by_name(tmp_path, rgb16, how, words):
    path = tmp_path / f"{how}.xisf"
    _damaged(path, rgb16, how)
    with pytest.raises(ImageReadError, match=words) as caught:
        read_image(path)
    assert str(path) in str(caught.value)


def test_the_size_limit_is_checked_before_the_pixels(tmp_path, rgb16):
    write_xisf(tmp_path / "big.xisf", rgb16)
    with pytest.raises(ImageReadError, match="over the limit of 500 px"):
        read_image(tmp_path / "big.xisf", max_pixels=500)


def test_a_star_frame_solves_from_xisf(tmp_path):
    camera, truth = Camera.from_fov(640, 480, 15.0), Rotation.random(random_state=21)
    sim = simulate_frame(camera, truth, max_mag=7.0, rng=3, sensor=get_sensor_preset("generic-cmos"))
    write_xisf(tmp_path / "stars.xisf", np.clip(sim.image, 0, 65535).astype(np.uint16), codec="zstd+sh")
    solution = solve_image(tmp_path / "stars.xisf")
    assert solution.solved, solution.reason
    assert attitude_error(solution.rot_cam_from_icrs, truth) < 2 * camera.pixel_scale_arcsec * ARCSEC
