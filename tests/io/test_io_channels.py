"""The colour-to-single-channel rule (startrack.io._channels): R + G + B in a wider type."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.io import to_single_channel


@pytest.fixture
def rgba16() -> np.ndarray:
    return np.random.default_rng(5).integers(0, 65536, size=(6, 7, 4)).astype(np.uint16)


def _exact_sum(rgb: np.ndarray) -> np.ndarray:
    """R + G + B in Python integers (object dtype): no overflow, no rounding."""
    return rgb[..., :3].astype(object).sum(axis=-1)


def test_grey_is_returned_unchanged():
    grey = np.arange(12, dtype=np.uint16).reshape(3, 4)
    out = to_single_channel(grey)
    assert out is grey


def test_default_is_sum_of_rgb_ignoring_alpha(rgba16):
    out = to_single_channel(rgba16)
    assert out.dtype == np.uint32 and out.shape == (6, 7)
    np.testing.assert_array_equal(out.astype(object), _exact_sum(rgba16))
    other_alpha = rgba16.copy()
    other_alpha[..., 3] = np.arange(42).reshape(6, 7)
    np.testing.assert_array_equal(to_single_channel(other_alpha), out)
    np.testing.assert_array_equal(to_single_channel(rgba16[..., :3]), out)


@pytest.mark.parametrize(("dtype", "sum_dtype"), [
    (np.uint8, np.uint16), (np.uint16, np.uint32), (np.uint32, np.uint64),
    (np.int8, np.int32), (np.int16, np.int32), (np.int32, np.int64),
])
def test_integer_sum_cannot_overflow(dtype, sum_dtype):
    top = np.iinfo(dtype).max
    rgb = np.full((2, 3, 3), top, dtype=dtype)
    rgb[0, 0] = [top, 0, 1]
    out = to_single_channel(rgb)
    assert out.dtype == sum_dtype
    assert int(out[1, 2]) == 3 * int(top)
    assert int(out[0, 0]) == int(top) + 1


def test_white_uint8_sums_to_765_without_rescaling():
    white = np.full((2, 2, 3), 255, dtype=np.uint8)
    out = to_single_channel(white)
    assert out.dtype == np.uint16
    np.testing.assert_array_equal(out, 765)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_float_sum_keeps_its_precision(dtype):
    rgb = np.array([[[0.5, 1.25, -2.0], [2.0**100, 2.0**101, 2.0**100]]], dtype=dtype)
    out = to_single_channel(rgb)
    assert out.dtype == dtype and out.shape == (1, 2)
    np.testing.assert_array_equal(out, np.array([[-0.25, 2.0**102]], dtype=dtype))


@pytest.mark.parametrize(
    ("channel", "index"),
    [("r", 0), ("G", 1), (" b ", 2), (0, 0), (1, 1), (2, 2), (np.int64(2), 2)],
)
def test_named_channel_keeps_native_dtype(rgba16, channel, index):
    out = to_single_channel(rgba16, channel)
    assert out.dtype == np.uint16
    np.testing.assert_array_equal(out, rgba16[..., index])


def test_single_plane_is_squeezed_and_channel_ignored():
    a = np.arange(6, dtype=np.uint8).reshape(2, 3, 1)
    for channel in (None, "g", 2):
        out = to_single_channel(a, channel)
        assert out.shape == (2, 3) and out.dtype == np.uint8
        np.testing.assert_array_equal(out, a[..., 0])


@pytest.mark.parametrize("channel", [None, "r", "g", "b", 1])
def test_grey_alpha_gives_grey_plane_never_alpha(channel):
    grey = np.arange(6, dtype=np.uint8).reshape(2, 3)
    la = np.dstack([grey, np.full_like(grey, 255)])
    out = to_single_channel(la, channel)
    assert out.dtype == np.uint8
    np.testing.assert_array_equal(out, grey)


@pytest.mark.parametrize("channel", ["r", "B", 0, 2])
def test_valid_channel_is_ignored_for_2d(channel):
    grey = np.arange(6, dtype=np.float32).reshape(2, 3)
    assert to_single_channel(grey, channel) is grey


@pytest.mark.parametrize("channel", ["a", "alpha", "rgb", 3, -1, 1.0, True, ""])
@pytest.mark.parametrize("shape", [(6, 7, 4), (6, 7, 3), (6, 7, 1), (6, 7)])
def test_bad_channel_is_refused(channel, shape):
    with pytest.raises(InvalidInputError, match="channel"):
        to_single_channel(np.zeros(shape, np.uint16), channel)


@pytest.mark.parametrize("shape", [(5,), (4, 4, 0), (4, 4, 5), (2, 3, 4, 3)])
def test_bad_shape_is_refused(shape):
    with pytest.raises(InvalidInputError, match="shape"):
        to_single_channel(np.zeros(shape))


@pytest.mark.parametrize("dtype", [complex, str])
def test_non_numeric_colour_is_refused(dtype):
    with pytest.raises(InvalidInputError, match="dtype"):
        to_single_channel(np.zeros((2, 2, 3), dtype=dtype))
