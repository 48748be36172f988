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


def test_candidate_axes_point_to_plus_x_whatever_lapack_chose():
    from startrack.rate._streak_find import _axes

    angles = np.radians([0.0, 30.0, 135.0, 180.0, 250.0, 300.0])
    u = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    cov = 100.0 * u[:, :, None] * u[:, None, :] + 0.5 * np.eye(2)  # long along u, 1/sqrt(2) px across
    cov = np.concatenate([cov, np.diag([0.5, 100.5])[None]])  # and an exactly vertical one
    along, across, axis = _axes(cov)
    assert np.allclose(along, 100.5) and np.allclose(across, 0.5)  # px^2
    assert np.allclose(np.abs(np.sum(axis[:-1] * u, axis=1)), 1.0)  # the same lines as u
    assert np.all(axis[:-1, 0] > 0) and np.array_equal(np.abs(axis[-1]), [0.0, 1.0]) and axis[-1, 1] > 0
