"""Image readers and writers, and star lists.

* :func:`read_image` reads FITS, PNG, JPEG and TIFF files (or wraps an array) into a
  single-channel :class:`Image`, keeping the native dtype; colour follows the rule of
  :func:`to_single_channel`; images larger than :data:`DEFAULT_MAX_PIXELS` are refused from their
  header, before any pixel is decoded (raise the limit with ``max_pixels``).
* :func:`write_png`, :func:`write_tiff` and :func:`write_fits` write by the rules of
  :mod:`startrack.io._atomic` (never over an input, a complete write or nothing).
* :func:`mosaic_to_plane` turns a raw colour-filter mosaic (Bayer, X-Trans) from a camera's own
  software into the plane ``read_image`` would read from its FITS or RAW file.
* :func:`read_star_list` reads CSV star lists (x, y in our 0-based pixel convention), SExtractor's
  catalogs and astrometry.net's xylists (their 1-based positions made ours).
* :func:`in_name_order` orders a folder's images by name, numbers compared as numbers.

Problems with a file raise :class:`startrack.errors.ImageReadError` (a ValueError) naming the
file and the problem; bad arguments raise :class:`startrack.errors.InvalidInputError`.

The names are imported on first use, so that ``startrack.io._atomic`` (used by the caches) does
not load astropy's FITS code or Pillow.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._atomic import atomic_path, discard, open_output, remove_stale_temps, temp_name, write_output
    from ._cfa import mosaic_to_plane
    from ._channels import channel_index, to_single_channel
    from ._file_order import in_name_order, natural_key
    from ._fits_cards import BITPIX_VALUES
    from ._fitsfile import fits_bytes, write_fits
    from ._heif import HEIF_BRANDS, is_heif
    from ._image import IMAGE_SUFFIXES, RAW_SUFFIXES, SUPPORTED_FORMATS, Image, pillow_raster_format, read_image
    from ._json_file import read_json_file
    from ._limits import (
        DEFAULT_MAX_PIXELS,
        ENV_VAR,
        check_image_size,
        max_pixels_limit,
        resolve_max_pixels,
        set_max_pixels,
    )
    from ._mosaic import describe_mosaic
    from ._png16 import warm_up_png16
    from ._raw import bayer_cells, cell_origin, full_resolution_xy, read_raw
    from ._solution_json import solution_to_dict, streak_fields
    from ._solved_fits import write_solved_fits
    from ._starlist import read_star_list, star_list_image_size
    from ._targets import STDOUT, output_target, protect_inputs
    from ._tiff import tiff_bytes
    from ._track_csv import COLUMNS, error_row, track_csv_writer, track_row
    from ._truth_files import check_frame_path, index_row, truth_to_dict, write_frame, write_index, write_with_sidecar
    from ._wcs import read_wcs, solution_wcs, wcs_header, write_wcs
    from ._writers import png_bytes, write_png, write_tiff
    from ._xisf import xisf_size

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
