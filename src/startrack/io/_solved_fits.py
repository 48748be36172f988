"""The image a solve read, written as a FITS file with the solution's WCS (astrometry.net's
``.new`` file; ``startrack solve IMAGE --new-fits OUT.fits``).

The pixels are those startrack solved: a FITS file's image plane in its own type (a colour-filter
mosaic's full-resolution plane, :mod:`._mosaic`), a photo's grey plane (R + G + B), a RAW file's
plane, so that the WCS (whose pixels are those of the plane) and the data agree. A FITS file's
cards are kept (OBJECT, EXPTIME, DATE-OBS, its history...), less its structural ones, a checksum
the new data would contradict, the cards of any WCS it had (primary and alternate: CTYPE, CRVAL,
CRPIX, CD, PC, CDELT, CROTA, PV, SIP's A / B / AP / BP, ...) and, once read through the mosaic's
kernel, the Bayer cards; the solution's TAN(-SIP) WCS (:func:`._wcs.wcs_header`) takes their
place. Other formats' metadata (EXIF) have no FITS cards and are left out.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from scipy.spatial.transform import Rotation

from ..camera import Camera
from ._fitsfile import write_fits
from ._image import Image
from ._wcs import wcs_header

WCS_CARD = re.compile(r"^(WCSAXES|WCSNAME|CTYPE\d|CRVAL\d|CRPIX\d|CDELT\d|CUNIT\d|CROTA\d|CD\d_\d|PC\d_\d|PV\d_\d+|"
                      r"PS\d_\d+|CRDER\d|CSYER\d|LONPOLE|LATPOLE|RADESYS|RADECSYS|EQUINOX|"
                      r"[AB]P?_ORDER|[AB]P?_\d+_\d+|[AB]_DMAX|SIPFITPX|IMAGEW|IMAGEH)[A-Z]?$")
"""FITS cards of a WCS, primary or alternate (a letter after the name), which the new WCS replaces."""

CHECKSUM_CARDS = frozenset({"CHECKSUM", "DATASUM"})
"""The old checksums, which the written data would contradict."""

MOSAIC_CARDS = frozenset({"BAYERPAT", "XBAYROFF", "YBAYROFF"})
"""A mosaic's pattern, dropped once the mosaic has been read into one plane."""


def carried_cards(image: Image) -> dict[str, Any]:
    """The cards of a FITS image's header to write again (module docstring); none for an image
    of another format (whose header holds no FITS cards)."""
    header = image.header
    if "SIMPLE" not in header and "XTENSION" not in header:
        return {}
    stale = CHECKSUM_CARDS | (MOSAIC_CARDS if image.mosaic is not None else frozenset())
    return {key: value for key, value in header.items() if key not in stale and not WCS_CARD.match(key)}


def write_solved_fits(path: str | os.PathLike, image: Image, rot_cam_from_icrs: Rotation, camera: Camera, *,
                      inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``image``'s plane (H, W) with its carried cards (:func:`carried_cards`) and the WCS
    of the solution (``rot_cam_from_icrs`` and the fitted ``camera``) to ``path``, by the rules of
    :mod:`startrack.io._atomic` (never over one of ``inputs`` or the image read)."""
    header: dict[str, Any] = carried_cards(image)
    for card in wcs_header(rot_cam_from_icrs, camera).cards:
        if card.keyword == "HISTORY":
            header["HISTORY"] = [*_as_list(header.get("HISTORY")), card.value]
        else:
            header[card.keyword] = (card.value, card.comment)
    source = "an array" if image.path is None else Path(image.path).name
    header["HISTORY"] = [*_as_list(header.get("HISTORY")), f"startrack: the image of {source} as solved"]
    return write_fits(path, image.data, header, inputs=[*inputs, *([image.path] if image.path else [])])


def _as_list(value: Any) -> list:
    """A HISTORY or COMMENT value as a list of lines (none, one, or several)."""
    if value is None:
        return []
    return list(value) if isinstance(value, list | tuple) else [value]
