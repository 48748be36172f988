"""Input checks and conversion of the image to the float32 plane the detector works on."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ._channels import to_single_channel

MIN_SIDE_PX = 2
"""Smallest accepted image side, in pixels."""


@dataclass(frozen=True)
class PreparedImage:
    """The plane the detector works on.

    Attributes
    ----------
    data : ndarray, shape (H, W)
        Pixel values in the input's units: the integer plane itself (not copied; stages
        convert what they read), or a float32 copy in which every non-finite pixel is NaN.
    invalid : ndarray of bool, shape (H, W), or None
        True where the input was NaN or infinite; None when every pixel was finite. The
        stages leave these pixels out of the background statistics and give them no weight
        in a spot.
    """

    data: NDArray
    invalid: NDArray[np.bool_] | None


def pixel_array(image: object) -> NDArray:
    """``image`` as an array: the array ``.data`` of an object that holds its pixels so (a
    :class:`startrack.io.Image`, an astropy HDU), else ``np.asarray(image)``."""
    if not isinstance(image, np.ndarray) and isinstance(getattr(image, "data", None), np.ndarray):
        return image.data  # type: ignore[attr-defined]
    return np.asarray(image)


def prepare_image(image: NDArray, channel: str | int | None = None) -> PreparedImage:
    """Check ``image``, reduce it to one channel, make float planes float32 with NaN for
    every non-finite pixel.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, C)
        uint8, uint16, any integer, bool, float32 or float64, in either byte order (the
        big-endian arrays of FITS files are converted). Colour images are reduced by
        :func:`startrack.detect._channels.to_single_channel` (R + G + B by default). An object
        that holds its pixels as an array ``.data`` (a :class:`startrack.io.Image`, an astropy
        HDU) is taken for them.
    channel : {None, "r", "g", "b", 0, 1, 2}
        Plane of a colour image to use instead of R + G + B (by name or index).

    Returns
    -------
    PreparedImage

    Raises
    ------
    InvalidInputError
        Not 2-D / 3-D, a side shorter than 2 px, empty, not numeric, or no finite pixel.
    """
    array = pixel_array(image)
    if not array.dtype.isnative:  # big-endian data (astropy.io.fits.getdata's): in native order
        array = array.astype(array.dtype.newbyteorder("="))
    if array.dtype == np.bool_:
        array = array.astype(np.uint8)
    if not (np.issubdtype(array.dtype, np.integer) or np.issubdtype(array.dtype, np.floating)):
        raise InvalidInputError(f"image must hold integers or floats, got dtype {array.dtype}")
    plane = to_single_channel(array, channel)
    if min(plane.shape) < MIN_SIDE_PX:
        raise InvalidInputError(
            f"image must be at least {MIN_SIDE_PX} x {MIN_SIDE_PX} px, got shape {array.shape}"
        )
    if np.issubdtype(plane.dtype, np.integer):
        return PreparedImage(plane, None)
    data = plane.astype(np.float32)
    finite = np.isfinite(data)
    if finite.all():
        return PreparedImage(data, None)
    if not finite.any():
        raise InvalidInputError("image has no finite pixel (all NaN or infinite)")
    data[~finite] = np.nan
    return PreparedImage(data, ~finite)
