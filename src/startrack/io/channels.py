"""The one rule that turns a colour image into the single channel startrack works on.

DESIGN.md §3 (Images): colour images are reduced to one channel by an explicit, documented
rule. The rule, used by every reader in :mod:`startrack.io`:

* a 2-D array is already single-channel and is returned unchanged;
* an array of shape (H, W, 1) is squeezed to (H, W), dtype unchanged;
* an array of shape (H, W, 3) (RGB) or (H, W, 4) (RGBA) is reduced

  - by default (``channel=None``) to the mean of R, G and B, as float32 (computed in float64
    and then rounded, so it is exact to float32 precision for 8- and 16-bit data); alpha is
    ignored;
  - with ``channel`` = ``"r"``, ``"g"``, ``"b"`` (any case) or ``0``, ``1``, ``2`` to that
    one channel, keeping the native dtype (uint8 stays uint8, uint16 stays uint16).

The values are never rescaled (no division by 255 or 65535).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError

CHANNEL_NAMES: dict[str, int] = {"r": 0, "g": 1, "b": 2}
"""Names accepted for ``channel`` and the index of the colour plane they select."""

COLOUR_CHANNEL_COUNTS = (1, 3, 4)
"""Numbers of channels (last axis) that a colour array may have: grey, RGB, RGBA."""


def channel_index(channel: str | int | None) -> int | None:
    """The plane index (0, 1, 2) that ``channel`` selects, or None for the RGB mean.

    Raises
    ------
    InvalidInputError
        If ``channel`` is not None, "r", "g", "b" (any case) or 0, 1, 2.
    """
    if channel is None:
        return None
    if isinstance(channel, str) and channel.strip().lower() in CHANNEL_NAMES:
        return CHANNEL_NAMES[channel.strip().lower()]
    is_int = isinstance(channel, int | np.integer) and not isinstance(channel, bool)
    if is_int and 0 <= channel <= 2:
        return int(channel)
    raise InvalidInputError(
        f"channel must be None (mean of R, G, B), 'r', 'g', 'b' or 0, 1, 2; got {channel!r}"
    )


def to_single_channel(array: NDArray, channel: str | int | None = None) -> NDArray:
    """Reduce an image to one channel by the rule in this module's docstring.

    Parameters
    ----------
    array : ndarray, shape (H, W) or (H, W, C) with C in {1, 3, 4}
        Image, channels last (RGB or RGBA order).
    channel : {None, "r", "g", "b", 0, 1, 2}
        None for the float32 mean of R, G and B; otherwise the plane to keep. Ignored for
        single-channel input (after checking it is a valid value).

    Returns
    -------
    ndarray, shape (H, W)
        float32 for the RGB mean, the input dtype otherwise.

    Raises
    ------
    InvalidInputError
        If the array is not 2-D or 3-D with 1, 3 or 4 channels, or ``channel`` is not valid.
    """
    index = channel_index(channel)
    array = np.asarray(array)
    if array.ndim == 2:
        return array
    if array.ndim != 3 or array.shape[-1] not in COLOUR_CHANNEL_COUNTS:
        raise InvalidInputError(
            "image array must have shape (H, W) or (H, W, C) with C = 1 (grey), 3 (RGB) or "
            f"4 (RGBA), got shape {array.shape}"
        )
    if array.shape[-1] == 1:
        return array[..., 0]
    if index is not None:
        return array[..., index]
    return np.mean(array[..., :3], axis=-1, dtype=np.float64).astype(np.float32)
