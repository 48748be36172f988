"""Reduce a colour image to the single channel the detector works on (DESIGN.md §3, "Images").

The rule, for an array of shape (H, W, C):

* C = 1: that plane.
* C = 2 (grey + alpha, Pillow's ``"LA"`` mode): the grey plane; alpha is ignored.
* C = 3 (RGB) or C = 4 (RGBA): the **sum** R + G + B; alpha is ignored.

The sum, not the mean, keeps the counts whole (an 8-bit RGB image becomes integers 0-765),
keeps the photon statistics of the three channels, and is proportional to a flat-spectrum
luminance; stars of any colour contribute in all three bands. ``channel=i`` picks plane ``i``
instead (for example the green plane of a Bayer-interpolated image). Values are never rescaled.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError

_SUM_DTYPE = {1: np.uint16, 2: np.uint32, 4: np.int64, 8: np.int64}


def _sum_dtype(dtype: np.dtype) -> np.dtype:
    """Dtype that holds the sum of three values of ``dtype`` without overflow."""
    if dtype == np.bool_:
        return np.dtype(np.uint8)
    if np.issubdtype(dtype, np.unsignedinteger):
        return np.dtype(_SUM_DTYPE[dtype.itemsize])
    if np.issubdtype(dtype, np.integer):
        return np.dtype(np.int64 if dtype.itemsize >= 4 else np.int32)
    if np.issubdtype(dtype, np.floating):
        return np.dtype(np.float64) if dtype.itemsize > 4 else np.dtype(np.float32)
    raise InvalidInputError(f"image dtype must be numeric (integer or float), got {dtype}")


def to_single_channel(image: NDArray, channel: int | None = None) -> NDArray:
    """One 2-D plane from a grey or colour image, by the rule in the module docstring.

    Parameters
    ----------
    image : ndarray, shape (H, W) or (H, W, C) with C in 1..4
        Grey image, or a colour image with channels last (as Pillow and imageio give them).
    channel : int or None
        Plane to take from a colour image (0 <= channel < C). None applies the default rule:
        R + G + B for 3 or 4 channels, the first plane for 1 or 2.

    Returns
    -------
    ndarray, shape (H, W)
        The input itself for a 2-D image; a view for a chosen plane; a new array for a sum
        (integer inputs are summed in a wider integer type, floats in their own precision).

    Raises
    ------
    InvalidInputError
        If the array is not 2-D or 3-D with 1-4 channels, or ``channel`` is out of range.
    """
    image = np.asarray(image)
    if image.ndim == 2:
        if channel not in (None, 0):
            raise InvalidInputError(f"channel must be None or 0 for a 2-D image, got {channel!r}")
        return image
    if image.ndim != 3 or not 1 <= image.shape[2] <= 4:
        raise InvalidInputError(
            "image must be 2-D (H, W) or colour (H, W, C) with 1 to 4 channels, "
            f"got shape {image.shape}"
        )
    n_channels = image.shape[2]
    if channel is not None:
        if not (isinstance(channel, int | np.integer) and 0 <= channel < n_channels):
            raise InvalidInputError(
                f"channel must be an integer in [0, {n_channels - 1}] for this image, got {channel!r}"
            )
        return image[:, :, int(channel)]
    if n_channels <= 2:
        return image[:, :, 0]
    rgb = image[:, :, :3]
    return np.add(np.add(rgb[:, :, 0], rgb[:, :, 1], dtype=_sum_dtype(image.dtype)), rgb[:, :, 2])
