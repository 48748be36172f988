"""Image readers and writers, and star lists.

* :func:`read_image` reads FITS, PNG, JPEG and TIFF files (or wraps an array) into a
  single-channel :class:`Image`, keeping the native dtype; colour follows the rule of
  :func:`to_single_channel`.
* :func:`write_png`, :func:`write_tiff` and :func:`write_fits` write atomically.
* :func:`read_star_list` reads CSV star lists (x, y in our 0-based pixel convention).

Problems with a file raise :class:`startrack.errors.ImageReadError` (a ValueError) naming the
file and the problem; bad arguments raise :class:`startrack.errors.InvalidInputError`.
"""

from __future__ import annotations

from .channels import to_single_channel
from .fitsfile import write_fits
from .image import SUPPORTED_FORMATS, Image, read_image
from .starlist import read_star_list
from .writers import write_png, write_tiff

__all__ = [
    "SUPPORTED_FORMATS",
    "Image",
    "read_image",
    "read_star_list",
    "to_single_channel",
    "write_fits",
    "write_png",
    "write_tiff",
]
