"""Dark and fixed-pattern subtraction: dark frames, median frames, row-wise dark reference pixels.

* **Dark / median frame** (Huffman 2006 §4.1): the per-pixel median of
  several frames of a sequence is subtracted before thresholding. Stars move between frames
  (or are absent from lens-cap darks), so the median keeps the fixed pattern: hot pixels,
  amp glow, bias structure (``realdata/UBNanosatLab-openstartracker/median_image.png`` is
  such a map). :func:`median_frame` builds one, :func:`subtract_dark` applies it. The frame's
  own level is kept: the median of the dark is added back, so the background stays positive
  for integer images and the detector's background model measures the sky as before.
* **Row-wise dark reference** (Jacobs 1995 §2.2.1.2.2.1.2, App C.1, §8.5–8.6): sensors with
  optically shielded columns at the start and end of each row give that row's dark level; the
  AC-coupled video chain of the seed's camera drifts along the readout, so a per-row value beats
  one for the frame. :func:`subtract_row_reference` subtracts each row's mean over those columns
  and cuts them off; the caller adds the leading count back to x.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError


def median_frame(frames) -> NDArray[np.float32]:
    """Per-pixel median of a sequence of frames (K, H, W) or a list of (H, W) arrays, as
    float32 (NaN pixels left out)."""
    stack = np.asarray(frames)
    if stack.ndim != 3 or stack.shape[0] < 1:
        raise InvalidInputError(f"frames must be K >= 1 frames of shape (H, W), got {stack.shape}")
    if np.issubdtype(stack.dtype, np.integer):
        return np.median(stack, axis=0).astype(np.float32)
    return np.nanmedian(stack.astype(np.float32), axis=0)


def subtract_dark(image: NDArray, dark: NDArray) -> NDArray[np.float32]:
    """``image - dark + median(dark)`` as float32 (module docstring); NaN where the dark frame is
    NaN or infinite (the detector leaves such pixels out), the median over its finite pixels.

    Raises
    ------
    InvalidInputError
        ``dark`` is not 2-D of the image's shape.
    """
    dark = np.asarray(dark)
    if dark.ndim == 3:  # a colour map (e.g. an RGB PNG): the colour rule applies to it too
        from ..io import to_single_channel
        dark = to_single_channel(dark)
    if dark.shape != image.shape:
        raise InvalidInputError(
            f"dark_frame must have the image's shape {image.shape}, got {dark.shape}")
    dark = dark.astype(np.float32)
    finite = np.isfinite(dark)
    if not finite.all():  # a NaN or infinite dark pixel leaves that pixel out (NaN), as a NaN pixel of the image
        dark = np.where(finite, dark, np.float32(np.nan))
    offset = np.float32(np.median(dark[finite])) if finite.any() else np.float32(0.0)
    out = image.astype(np.float32)
    out -= dark
    out += offset
    return out


def subtract_row_reference(image: NDArray, leading: int, trailing: int
                           ) -> NDArray[np.float32]:
    """Subtract each row's mean over its ``leading`` first and ``trailing`` last columns (the
    dark reference pixels), and return the remaining columns, float32, shape
    (H, W - leading - trailing).

    Raises
    ------
    InvalidInputError
        No reference column, or fewer than 2 columns left.
    """
    h, w = image.shape
    if leading + trailing < 1 or w - leading - trailing < 2:
        raise InvalidInputError(
            f"dark_columns must name at least one reference column and leave 2 image columns, "
            f"got ({leading}, {trailing}) for an image {w} px wide")
    ref = np.concatenate([image[:, :leading], image[:, w - trailing:]], axis=1).astype(np.float64)
    level = np.nanmean(ref, axis=1) if np.isnan(ref).any() else ref.mean(axis=1)
    out = image[:, leading: w - trailing].astype(np.float32)
    out -= level.astype(np.float32)[:, None]
    return out
