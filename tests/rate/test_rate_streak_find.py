"""The compiled block sums of the streak search (startrack.rate._streak_find.binned) take every
pixel type a reader can give, big-endian FITS integers included, and sum as numpy does."""

import numpy as np
import pytest

from startrack.rate._streak_find import binned


@pytest.mark.parametrize("dtype", ["<u2", ">u2", ">i2", ">i4", "float16", "<f4", ">f8", "int64", "bool"])
def test_block_sums_equal_numpy_for_every_pixel_type(dtype):
    image = np.random.default_rng(1).poisson(50, (37, 42)).astype(dtype)  # trailing rows and columns dropped
    expected = image[:36, :40].astype(np.float64).reshape(9, 4, 10, 4).sum(axis=(1, 3))
    np.testing.assert_array_equal(binned(image, 4), expected)
