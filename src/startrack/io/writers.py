"""Write images as PNG or TIFF, atomically, keeping their bit depth.

Both writers take the values as they are: no scaling, no clipping, no rounding. A float image
must be converted by the caller with an explicit rule (e.g.
``np.clip(np.round(a), 0, 65535).astype(np.uint16)``); PNG refuses floats, TIFF accepts grey
float32. Each file is written to a temporary file in the same folder and renamed, so nothing
half-written remains if an error occurs. FITS is written by :func:`startrack.io.write_fits`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image as PILImage

from ..errors import InvalidInputError
from .atomic import atomic_path
from .tiff import tiff_bytes


def _png_array(array: NDArray) -> NDArray:
    """The array in a layout Pillow writes losslessly, or InvalidInputError."""
    grey = array.ndim == 2 and array.dtype.kind == "u" and array.dtype.itemsize in (1, 2)
    rgb8 = array.ndim == 3 and array.shape[-1] in (3, 4) and array.dtype == np.uint8
    if array.dtype.kind == "f":
        raise InvalidInputError(
            f"PNG cannot store float pixels (got {array.dtype}); convert explicitly, e.g. "
            "np.clip(np.round(a), 0, 65535).astype(np.uint16), or write FITS / TIFF instead"
        )
    if not (grey or rgb8) or array.size == 0:
        raise InvalidInputError(
            "PNG image must be a non-empty (H, W) uint8 or uint16 array, or (H, W, 3|4) uint8; "
            f"got shape {array.shape} and dtype {array.dtype}"
        )
    return np.ascontiguousarray(array, dtype=array.dtype.newbyteorder("="))


def write_png(path: str | os.PathLike, array: NDArray) -> Path:
    """Write a PNG, 8-bit for uint8 and 16-bit for uint16.

    Parameters
    ----------
    path : str or Path
        The file to write (replaced atomically).
    array : ndarray
        (H, W) uint8 or uint16 greyscale, or (H, W, 3) RGB / (H, W, 4) RGBA uint8.

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    InvalidInputError
        For float arrays (convert explicitly first), other dtypes or shapes, or a missing folder.
    """
    data = _png_array(np.asarray(array))
    with atomic_path(path) as tmp:
        PILImage.fromarray(data).save(tmp, format="PNG")
    return Path(path)


def write_tiff(path: str | os.PathLike, array: NDArray) -> Path:
    """Write an uncompressed TIFF: (H, W) uint8 / uint16 / float32, or (H, W, 3) uint8 / uint16.

    Returns
    -------
    Path
        The path written (replaced atomically).

    Raises
    ------
    InvalidInputError
        For other dtypes or shapes, or a missing folder.
    """
    data = tiff_bytes(np.asarray(array))
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)
