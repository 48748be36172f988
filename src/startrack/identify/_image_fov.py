"""The field of view an image's header states: a photo's EXIF focal length, an astronomy camera's
FITS focal length and pixel size.

A solve given no field of view searches :data:`._registry.DEFAULT_FOV_RANGE_DEG` (3 to 100 deg).
A lens beyond it (a 12-14 mm lens on a full-frame camera, 104-113 deg; a phone's ultra-wide) or a
telescope below it is found only with its field. Cameras write it, in this order of preference:

1. ``FocalLengthIn35mmFilm`` (EXIF): the focal length that gives a full-frame (36 x 24 mm) camera
   the same field. Makers scale by the diagonal (CIPA DC-008) or the width; the two differ by 4 %
   on a 4:3 sensor. The diagonal is used: it does not depend on how the image is held.
2. ``FocalLength`` with ``FocalPlaneXResolution``, ``FocalPlaneYResolution`` and
   ``FocalPlaneResolutionUnit`` (EXIF, most interchangeable-lens cameras): the sensor's size is
   the camera's image size (``ExifImageWidth`` x ``ExifImageHeight``) over those resolutions.
3. A celestial FITS WCS (``CTYPE1`` of RA, DEC, GLON, GLAT, ELON or ELAT; a plate solve's,
   astrometry.net's or ours): its scale along the image's rows, from ``CD1_1`` and ``CD2_1`` (deg
   per px), else ``CDELT1`` with ``PC1_1`` and ``PC2_1`` (1 and 0 when missing), through a
   gnomonic projection.
4. ``FOCALLEN`` (mm) with ``XPIXSZ`` (um, the binned pixel's width, MaxIm DL's convention) (FITS,
   as N.I.N.A., SharpCap and MaxIm DL write them).

A cropped image keeps its camera's EXIF, so its field is smaller than the stated one: the solve
falls back on the default search when the stated field fails (:func:`stated_search_range`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ._registry import DEFAULT_FOV_RANGE_DEG, WIDE_MIN_FOV_DEG
from ._request import MAX_FOV_DEG, MIN_FOV_DEG

FULL_FRAME_DIAGONAL_MM = math.hypot(36.0, 24.0)
"""Diagonal of the 35 mm film frame (43.27 mm), the reference of ``FocalLengthIn35mmFilm``."""

STATED_FOV_TOLERANCE = 0.1
"""A stated field is searched within this fraction: the 4 % between the makers' two scalings, a
zoom's focal length rounded to a millimetre, and the focus distance's few per cent."""

_MM_PER_UNIT: dict[float, float] = {2: 25.4, 3: 10.0, 4: 1.0, 5: 1e-3}
"""Millimetres per ``FocalPlaneResolutionUnit`` (2 inch, 3 cm; 4 mm and 5 um are in later EXIF
versions' range of values)."""


def stated_fov_deg(header: Mapping[str, Any] | None, width: int, height: int) -> float | None:
    """The horizontal field of view (deg) of a ``width`` x ``height`` px image as its header states
    it (module docstring), or None when it states none, or one outside :data:`MIN_FOV_DEG` to
    :data:`MAX_FOV_DEG` (a value that is not a positive number is passed over, as a broken EXIF
    block is)."""
    if not header:
        return None
    tan_half_diagonal = _exif_35mm(header) or _exif_focal_plane(header)  # positive, or None
    tan_half = (_fits_wcs_scale(header, width) or _fits_pixel_size(header, width)) if tan_half_diagonal is None \
        else tan_half_diagonal * width / math.hypot(width, height)
    if tan_half is None:
        return None
    fov = math.degrees(2.0 * math.atan(tan_half))
    return fov if MIN_FOV_DEG <= fov <= MAX_FOV_DEG else None


def stated_search_range(header: Mapping[str, Any] | None, width: int, height: int) -> tuple[float, float] | None:
    """The range of horizontal fields (deg) to search first for an image whose header states a field
    (:func:`stated_fov_deg`) the default search does not reach, or None (no field stated, or one
    the default search covers: that search is then left as it is). A wide field is searched from
    :data:`._registry.WIDE_MIN_FOV_DEG` up (a crop of the frame narrows it; those searches share
    one database), a narrow one within :data:`STATED_FOV_TOLERANCE`."""
    fov = stated_fov_deg(header, width, height)
    if fov is None:
        return None
    lo, hi = fov * (1.0 - STATED_FOV_TOLERANCE), min(fov * (1.0 + STATED_FOV_TOLERANCE), MAX_FOV_DEG)
    if hi > DEFAULT_FOV_RANGE_DEG[1]:  # then lo > 81.8 deg, above WIDE_MIN_FOV_DEG
        return WIDE_MIN_FOV_DEG, hi
    if lo < DEFAULT_FOV_RANGE_DEG[0]:
        return max(lo, MIN_FOV_DEG), hi
    return None


def _positive(value: Any) -> float | None:
    """``value`` as a positive finite float, else None."""
    number = _finite(value)
    return number if number is not None and number > 0 else None


def _exif_35mm(header: Mapping[str, Any]) -> float | None:
    """tan of the half diagonal field from ``FocalLengthIn35mmFilm``."""
    focal = _positive(header.get("FocalLengthIn35mmFilm"))
    return None if focal is None else FULL_FRAME_DIAGONAL_MM / (2.0 * focal)


def _exif_focal_plane(header: Mapping[str, Any]) -> float | None:
    """tan of the half diagonal field from ``FocalLength`` and the focal plane's resolution."""
    focal = _positive(header.get("FocalLength"))
    code = header.get("FocalPlaneResolutionUnit", 2)
    unit = _MM_PER_UNIT.get(code) if isinstance(code, int | float) else None  # a list is no key
    sizes = [_positive(header.get(key)) for key in ("ExifImageWidth", "ExifImageHeight", "FocalPlaneXResolution",
                                                    "FocalPlaneYResolution")]
    if focal is None or unit is None:
        return None
    match sizes:
        case [float(width_px), float(height_px), float(x_res), float(y_res)]:
            return math.hypot(width_px / x_res, height_px / y_res) * unit / (2.0 * focal)
    return None


def _fits_pixel_size(header: Mapping[str, Any], width: int) -> float | None:
    """tan of the half horizontal field from FITS ``FOCALLEN`` (mm) and ``XPIXSZ`` (um)."""
    focal, pixel_um = _positive(header.get("FOCALLEN")), _positive(header.get("XPIXSZ"))
    if focal is None or pixel_um is None:
        return None
    return width * pixel_um * 1e-3 / (2.0 * focal)


CELESTIAL_AXES = ("RA", "DEC", "GLON", "GLAT", "ELON", "ELAT")
"""``CTYPE1`` prefixes of a celestial WCS whose scale :func:`_fits_wcs_scale` reads (the latitude
too: a WCS may put it on the first axis, and the scale along the rows is the same)."""


def _fits_wcs_scale(header: Mapping[str, Any], width: int) -> float | None:
    """tan of the half horizontal field from a celestial FITS WCS's scale along the rows (module
    docstring), or None when the header has none."""
    ctype = header.get("CTYPE1")
    column = _wcs_column(header) if isinstance(ctype, str) and ctype.upper().startswith(CELESTIAL_AXES) else None
    scale_deg = 0.0 if column is None else math.hypot(*column)
    return math.radians(scale_deg) * width / 2.0 if scale_deg > 0 else None  # the focal length is 1 / scale


def _wcs_column(header: Mapping[str, Any]) -> tuple[float, float] | None:
    """The change of the two world coordinates along a row, deg per px: (``CD1_1``, ``CD2_1``), else
    ``CDELT1`` times (``PC1_1``, ``PC2_1``) (1 and 0 when missing); None when a value is not finite."""
    scale: float | None
    if "CD1_1" in header or "CD2_1" in header:
        scale, keys = 1.0, (("CD1_1", 0.0), ("CD2_1", 0.0))
    else:
        scale, keys = _finite(header.get("CDELT1")), (("PC1_1", 1.0), ("PC2_1", 0.0))
    first, second = (_finite(header.get(key, default)) for key, default in keys)
    if scale is None or first is None or second is None:
        return None
    return scale * first, scale * second


def _finite(value: Any) -> float | None:
    """``value`` as a finite float, else None."""
    if isinstance(value, bool):
        return None
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        return None
    return number if math.isfinite(number) else None
