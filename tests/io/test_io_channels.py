"""The colour-to-single-channel rule (startrack.io.channels)."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.io import to_single_channel


@pytest.fixture
def rgba16() -> np.ndarray:
    return np.random.default_rng(5).integers(0, 65536, size=(6, 7, 4)).astype(np.uint16)


def test_grey_is_returned_unchanged():
    grey = np.arange(12, dtype=np.uint16).reshape(3, 4)
    out = to_single_channel(grey)
    assert out.dtype == np.uint16
    np.testing.assert_array_equal(out, grey)


def test_default_is_float32_mean_of_rgb_ignoring_alpha(rgba16):
    out = to_single_channel(rgba16)
    assert out.dtype == np.float32 and out.shape == (6, 7)
    exact = (rgba16[..., 0].astype(float) + rgba16[..., 1] + rgba16[..., 2]) / 3.0
    np.testing.assert_allclose(out, exact, rtol=2**-24)
    # alpha has no influence
    other_alpha = rgba16.copy()
    other_alpha[..., 3] = 0
    np.testing.assert_array_equal(to_single_channel(other_alpha), out)


def test_mean_is_not_rescaled():
    white = np.full((2, 2, 3), 255, dtype=np.uint8)
    np.testing.assert_array_equal(to_single_channel(white), 255.0)


@pytest.mark.parametrize(
    ("channel", "index"),
    [("r", 0), ("G", 1), ("b", 2), (0, 0), (1, 1), (2, 2), (np.int64(2), 2)],
)
def test_named_channel_keeps_native_dtype(rgba16, channel, index):
    out = to_single_channel(rgba16, channel)
    assert out.dtype == np.uint16
    np.testing.assert_array_equal(out, rgba16[..., index])


def test_single_plane_is_squeezed():
    a = np.arange(6, dtype=np.uint8).reshape(2, 3, 1)
    out = to_single_channel(a, "g")
    assert out.shape == (2, 3) and out.dtype == np.uint8


@pytest.mark.parametrize("channel", ["a", "alpha", 3, -1, 1.0, True, ""])
def test_bad_channel_is_refused(rgba16, channel):
    with pytest.raises(InvalidInputError, match="channel"):
        to_single_channel(rgba16, channel)


@pytest.mark.parametrize("shape", [(5,), (4, 4, 2), (4, 4, 5), (2, 3, 4, 3)])
def test_bad_shape_is_refused(shape):
    with pytest.raises(InvalidInputError, match="shape"):
        to_single_channel(np.zeros(shape))
