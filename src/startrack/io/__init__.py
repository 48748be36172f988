"""Image readers and writers, and star lists.

* :func:`read_image` reads FITS, PNG, JPEG and TIFF files (or wraps an array) into a
  single-channel :class:`Image`, keeping the native dtype; colour follows the rule of
  :func:`to_single_channel`; images larger than :data:`DEFAULT_MAX_PIXELS` are refused from their
  header, before any pixel is decoded (raise the limit with ``max_pixels``).
* :func:`write_png`, :func:`write_tiff` and :func:`write_fits` write by the rules of
  :mod:`startrack.io.atomic` (never over an input, a complete write or nothing).
* :func:`read_star_list` reads CSV star lists (x, y in our 0-based pixel convention).

Problems with a file raise :class:`startrack.errors.ImageReadError` (a ValueError) naming the
file and the problem; bad arguments raise :class:`startrack.errors.InvalidInputError`.

The names are imported on first use, so that ``startrack.io.atomic`` (used by the caches) does
not load astropy's FITS code or Pillow.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "DEFAULT_MAX_PIXELS": ".limits",
    "SUPPORTED_FORMATS": ".image",
    "Image": ".image",
    "read_image": ".image",
    "read_star_list": ".starlist",
    "to_single_channel": ".channels",
    "write_fits": ".fitsfile",
    "write_png": ".writers",
    "write_tiff": ".writers",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'startrack.io' has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
