"""The one size limit of every image startrack reads or renders, checked from the header first.

An image file says its size in its header (FITS NAXISn, the PNG IHDR, the JPEG frame header, the
TIFF tags); :func:`check_image_size` compares that with the limit *before* any pixel is decoded or
any array allocated, so a small file that claims a huge image (a "decompression bomb") costs
nothing. The limit is the same for every format and for the simulator:

* :data:`DEFAULT_MAX_PIXELS` (100 million pixels, e.g. 10,000 x 10,000; at about 6 bytes per pixel
  for a 16-bit image through detection, some 0.6 GB of memory);
* raised (or lowered) by the ``--max-pixels N`` option of the commands, the ``max_pixels``
  argument of :func:`startrack.io.read_image`, or the environment variable
  ``STARTRACK_MAX_PIXELS`` (applies to every command and the Python API);
* :func:`max_pixels_limit` sets it for a block of code (the commands use it for ``--max-pixels``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

from ..errors import ImageReadError, InvalidInputError

DEFAULT_MAX_PIXELS = 100_000_000
"""Largest image (width x height) read or rendered unless the limit is raised."""

ENV_VAR = "STARTRACK_MAX_PIXELS"

_LIMIT: ContextVar[int | None] = ContextVar("startrack_max_pixels", default=None)


def check_max_pixels(value, name: str = "max_pixels") -> int:
    """``value`` as a positive whole number of pixels, else InvalidInputError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | float | str) and not hasattr(value, "__index__"):
        raise InvalidInputError(f"{name} must be a whole number of pixels >= 1, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a whole number of pixels >= 1, got {value!r}") from None
    if not (math.isfinite(number) and number >= 1 and number == int(number)):
        raise InvalidInputError(f"{name} must be a whole number of pixels >= 1, got {value!r}")
    return int(number)


def current_max_pixels() -> int:
    """The limit in force: :func:`max_pixels_limit`, else ``$STARTRACK_MAX_PIXELS``, else the default."""
    limit = _LIMIT.get()
    if limit is not None:
        return limit
    env = os.environ.get(ENV_VAR, "").strip()
    if env:
        return check_max_pixels(env.replace("_", ""), f"environment variable {ENV_VAR}")
    return DEFAULT_MAX_PIXELS


def resolve_max_pixels(max_pixels: int | None) -> int:
    """A given ``max_pixels`` checked, or the limit in force when it is None."""
    return current_max_pixels() if max_pixels is None else check_max_pixels(max_pixels)


@contextmanager
def max_pixels_limit(max_pixels: int | None) -> Iterator[None]:
    """Use ``max_pixels`` as the limit inside this block (None keeps the one in force)."""
    token = _LIMIT.set(None if max_pixels is None else check_max_pixels(max_pixels))
    try:
        yield
    finally:
        _LIMIT.reset(token)


def set_max_pixels(max_pixels: int | None) -> None:
    """Use ``max_pixels`` from now on in this context (None keeps the one in force); the commands
    call it for ``--max-pixels`` inside :func:`max_pixels_limit`, which undoes it at the end."""
    if max_pixels is not None:
        _LIMIT.set(check_max_pixels(max_pixels))


def check_image_size(width: int, height: int, max_pixels: int | None, source: object) -> None:
    """Refuse an image of ``width`` x ``height`` above the limit, before it is decoded.

    Raises
    ------
    ImageReadError
        Naming ``source`` (a file, or what is rendered), the size, the limit and how to raise it.
    """
    limit = resolve_max_pixels(max_pixels)
    if width < 1 or height < 1:
        raise ImageReadError(f"{source}: image size {width} x {height} px is not valid")
    if width * height > limit:
        raise ImageReadError(
            f"{source}: image is {width} x {height} = {width * height:,} px, over the limit of {limit:,} px; "
            f"if you trust it, raise the limit (--max-pixels, max_pixels=, or {ENV_VAR})")
