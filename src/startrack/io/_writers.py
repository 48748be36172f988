"""Write images as PNG or TIFF, atomically, keeping their bit depth.

Both writers take the values as they are: no scaling, no clipping, no rounding. A float image
must be converted by the caller with an explicit rule (e.g.
``np.clip(np.round(a), 0, 65535).astype(np.uint16)``); PNG refuses floats, TIFF accepts grey
float32. Each file is written by the rules of :mod:`startrack.io._atomic`: never over an input, to
a temporary file in the same folder renamed only once complete, so nothing half-written remains
if an error occurs. FITS is written by :func:`startrack.io.write_fits`.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image as PILImage

from ..errors import InvalidInputError
from ._atomic import write_output
from ._tiff import tiff_bytes


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


def write_png(path: str | os.PathLike, array: NDArray, *, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write a PNG, 8-bit for uint8 and 16-bit for uint16.

    Parameters
    ----------
    path : str or Path
        The file to write, by the rules of :mod:`startrack.io._atomic` (replaced only by a
        complete file; ``-``, devices and FIFOs written through).
    array : ndarray
        (H, W) uint8 or uint16 greyscale, or (H, W, 3) RGB / (H, W, 4) RGBA uint8.
    inputs : iterable of paths
        Files that must not be replaced.

    Returns
    -------
    Path
        The path written.

    Raises
    ------
    InvalidInputError
        For float arrays (convert explicitly first), other dtypes or shapes, or a missing folder.
    """
    return write_output(path, png_bytes(array), inputs=inputs)


def png_bytes(array: NDArray) -> bytes:
    """The PNG encoding of an image (the layouts of :func:`write_png`), or InvalidInputError."""
    buffer = io.BytesIO()
    PILImage.fromarray(_png_array(np.asarray(array))).save(buffer, format="PNG")
    return buffer.getvalue()


def write_tiff(path: str | os.PathLike, array: NDArray, *, inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write an uncompressed TIFF: (H, W) uint8 / uint16 / float32, or (H, W, 3) uint8 / uint16.

    ``path`` and ``inputs`` as for :func:`write_png`.

    Returns
    -------
    Path
        The path written (replaced atomically).

    Raises
    ------
    InvalidInputError
        For other dtypes or shapes, or a missing folder.
    """
    return write_output(path, tiff_bytes(np.asarray(array)), inputs=inputs)
