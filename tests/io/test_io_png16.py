"""16-bit colour PNGs read with all their bits (startrack.io._png16), from files encoded here with
every row filter of the PNG specification (section 9)."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from startrack.errors import ImageReadError
from startrack.io import read_image
from startrack.simulate import render_gaussian_psf

COLOUR_TYPE = {2: 4, 3: 2, 4: 6}  # samples per pixel -> PNG colour type (grey + alpha, RGB, RGBA)


def chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def paeth(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    p = a + b - c
    pa, pb, pc = np.abs(p - a), np.abs(p - b), np.abs(p - c)
    return np.where((pa <= pb) & (pa <= pc), a, np.where(pb <= pc, b, c))


def filtered_rows(samples: np.ndarray, filters: tuple[int, ...]) -> bytes:
    """The IDAT stream's bytes before compression: row r filtered by ``filters[r % len]``."""
    height, width, channels = samples.shape
    raw = samples.astype(">u2").reshape(height, -1).view(np.uint8).astype(np.int64)
    bpp = 2 * channels
    out = []
    for r in range(height):
        x = raw[r]
        up = raw[r - 1] if r else np.zeros_like(x)
        a = np.concatenate([np.zeros(bpp, np.int64), x[:-bpp]])
        c = np.concatenate([np.zeros(bpp, np.int64), up[:-bpp]])
        kind = filters[r % len(filters)]
        guess = (np.zeros_like(x), a, up, (a + up) // 2, paeth(a, up, c))[kind]
        out.append(bytes([kind]) + ((x - guess) % 256).astype(np.uint8).tobytes())
    return b"".join(out)


def png16(samples: np.ndarray, filters: tuple[int, ...] = (0, 1, 2, 3, 4), interlace: int = 0,
          stream: bytes | None = None) -> bytes:
    """A 16-bit PNG of ``samples`` (H, W, C), C = 2, 3 or 4."""
    height, width, channels = samples.shape
    ihdr = struct.pack(">IIBBBBB", width, height, 16, COLOUR_TYPE[channels], 0, 0, interlace)
    data = filtered_rows(samples, filters) if stream is None else stream
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(data))
            + chunk(b"IEND", b""))


@pytest.mark.parametrize("channels", [3, 4, 2])
@pytest.mark.parametrize("filters", [(0,), (1,), (2,), (3,), (4,), (4, 3, 2, 1, 0)])
def test_every_sample_is_read_with_all_16_bits(tmp_path, channels, filters):
    samples = np.random.default_rng(channels).integers(0, 65536, (23, 37, channels))
    path = tmp_path / "colour16.png"
    path.write_bytes(png16(samples, filters))
    image = read_image(path)
    assert image.bit_depth == 16
    if channels == 2:  # grey + alpha: the grey
        np.testing.assert_array_equal(image.data, samples[..., 0])
        assert not image.colour
        return
    np.testing.assert_array_equal(image.data, samples[..., :3].sum(axis=-1))
    for index, name in enumerate("rgb"):
        np.testing.assert_array_equal(read_image(path, channel=name).data, samples[..., index])


def test_faint_stars_in_the_low_bytes_are_kept(tmp_path):
    """A sky of 780 counts with stars peaking 17-100 counts above it: all in the low byte, which
    Pillow would drop (the high byte alone is 3 everywhere)."""
    x, y = np.array([20.3, 60.7, 41.1]), np.array([15.2, 30.8, 44.5])
    light = render_gaussian_psf((60, 80), x, y, np.array([150.0, 500.0, 900.0]), 1.2)
    rgb = np.rint(np.stack([780 + light * share for share in (0.5, 1.0, 0.7)], axis=-1)).astype(np.int64)
    assert rgb.min() >= 768 and rgb.max() < 1024  # counts: the high byte is 3 in every sample
    path = tmp_path / "faint.png"
    path.write_bytes(png16(rgb))
    above = read_image(path).data.astype(float) - 3 * 780
    for xs, ys in zip(x, y, strict=True):
        assert above[int(round(ys)), int(round(xs))] > 10.0  # counts; 0 with the high bytes alone


def test_damaged_and_interlaced_files_are_refused(tmp_path):
    samples = np.random.default_rng(1).integers(0, 65536, (10, 12, 3))
    cases = {
        "short.png": (png16(samples, stream=filtered_rows(samples, (1,))[:-40]), "truncated or corrupt .*stop after"),
        "filter.png": (png16(samples, stream=b"\x07" + filtered_rows(samples, (0,))[1:]), "filter type 7"),
        "interlaced.png": (png16(samples, interlace=1), "interlaced"),
    }
    for name, (content, message) in cases.items():
        path = tmp_path / name
        path.write_bytes(content)
        with pytest.raises(ImageReadError, match=message):
            read_image(path)


def test_the_warm_up_compiles_the_loop_a_read_uses(tmp_path):
    """``startrack warm-up`` compiles the row-filter loop for the argument types a read passes (a
    read-only stream): one specialization, whichever ran first."""
    from startrack.io import warm_up_png16
    from startrack.io._png_kernels import unfilter

    path = tmp_path / "small.png"
    path.write_bytes(png16(np.ones((4, 5, 3), dtype=np.int64)))
    warm_up_png16()
    read_image(path)
    assert len(unfilter.signatures) == 1
