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

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "atomic_path": ".atomic",
    "discard": ".atomic",
    "open_output": ".atomic",
    "remove_stale_temps": ".atomic",
    "temp_name": ".atomic",
    "write_output": ".atomic",
    "channel_index": ".channels",
    "to_single_channel": ".channels",
    "fits_bytes": ".fitsfile",
    "write_fits": ".fitsfile",
    "IMAGE_SUFFIXES": ".image",
    "Image": ".image",
    "RAW_SUFFIXES": ".image",
    "SUPPORTED_FORMATS": ".image",
    "read_image": ".image",
    "DEFAULT_MAX_PIXELS": ".limits",
    "ENV_VAR": ".limits",
    "check_image_size": ".limits",
    "max_pixels_limit": ".limits",
    "resolve_max_pixels": ".limits",
    "set_max_pixels": ".limits",
    "bayer_cells": ".raw",
    "cell_origin": ".raw",
    "full_resolution_xy": ".raw",
    "read_raw": ".raw",
    "solution_to_dict": ".solution_json",
    "streak_fields": ".solution_json",
    "read_star_list": ".starlist",
    "STDOUT": ".targets",
    "output_target": ".targets",
    "protect_inputs": ".targets",
    "tiff_bytes": ".tiff",
    "COLUMNS": ".track_csv",
    "error_row": ".track_csv",
    "track_csv_writer": ".track_csv",
    "track_row": ".track_csv",
    "check_frame_path": ".truth_files",
    "index_row": ".truth_files",
    "truth_to_dict": ".truth_files",
    "write_frame": ".truth_files",
    "write_index": ".truth_files",
    "write_with_sidecar": ".truth_files",
    "read_wcs": ".wcs",
    "solution_wcs": ".wcs",
    "wcs_header": ".wcs",
    "write_wcs": ".wcs",
    "png_bytes": ".writers",
    "write_png": ".writers",
    "write_tiff": ".writers",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
