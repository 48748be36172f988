"""FITS header cards read leniently, and the cards that lay out the pixels checked strictly.

A card that only describes the image (``OBSERVER``, ``FOO``) and that astropy cannot parse (a value
with non-ASCII bytes, ``NAN``, ``1.2.3``, an unclosed quote) is left out of ``Image.header``, as
EXIF that Pillow cannot parse is; the pixels are still read. The cards that say how the pixels are
stored (``BITPIX``, ``NAXIS``, ``NAXIS1`` .. ``NAXISn``, ``BZERO``, ``BSCALE``) are checked before
any pixel is read: a wrong or missing one is an :class:`~startrack.errors.ImageReadError` naming the
file, the card and what would be valid.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from astropy.io import fits

from ..errors import ImageReadError, is_real_number

COMMENTARY = ("COMMENT", "HISTORY")
BITPIX_VALUES = (8, 16, 32, 64, -32, -64)
"""The values FITS allows for BITPIX (bits per pixel value; negative for IEEE floats)."""
MAX_NAXIS = 999
"""Largest NAXIS FITS allows."""

_MISSING = object()
_UNREADABLE = object()


def header_text(head: bytes) -> str:
    """Header bytes as text the way astropy's own reader decodes them: a byte that is not ASCII
    becomes ``?`` (so ``OBSERVER= 'M\xfcller'`` reads as ``'M?ller'`` on every path)."""
    return head.decode("ascii", errors="replace").replace("\ufffd", "?")


def header_to_dict(header: fits.Header) -> dict[str, Any]:
    """FITS header cards as a dict: keyword -> value; COMMENT and HISTORY as lists of strings.

    A card whose value astropy cannot parse is left out (module docstring); a keyword with no
    value maps to None.
    """
    out: dict[str, Any] = {}
    for card in header.cards:
        try:
            key, value = card.keyword, card.value
        except fits.VerifyError:
            continue
        if not key:
            continue
        if key in COMMENTARY:
            out.setdefault(key, []).append(str(value))
        elif isinstance(value, bool | int | float | str):
            out[key] = value
        else:  # astropy's Undefined (a keyword with no value)
            out[key] = None
    return out


def _value(header: fits.Header, key: str) -> Any:
    """The parsed value of a card, ``_MISSING`` when there is none, ``_UNREADABLE`` when astropy
    cannot parse it."""
    if key not in header:
        return _MISSING
    try:
        return header.cards[key].value
    except fits.VerifyError:
        return _UNREADABLE


def _shown(value: Any) -> str:
    if value is _MISSING:
        return "missing"
    if value is _UNREADABLE:
        return "not readable"
    return repr(value)


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _refuse(path: Path, key: str, value: Any, valid: str) -> ImageReadError:
    return ImageReadError(f"{path}: FITS header card {key} is {_shown(value)}; {valid}")


def check_layout_cards(header: fits.Header, path: Path) -> None:
    """Refuse a header whose BITPIX, NAXIS, NAXISn, BZERO or BSCALE cannot describe pixel data.

    Parameters
    ----------
    header : astropy.io.fits.Header
        The header of the HDU about to be read.
    path : Path
        The file, for the message.

    Raises
    ------
    ImageReadError
        Naming the file, the card, its value (or that it is missing or not readable) and the
        values FITS allows.
    """
    bitpix = _value(header, "BITPIX")
    if not (_is_int(bitpix) and bitpix in BITPIX_VALUES):
        raise _refuse(path, "BITPIX", bitpix, "it must be one of 8, 16, 32, 64, -32, -64 (bits per pixel value)")
    naxis = _value(header, "NAXIS")
    if not (_is_int(naxis) and 0 <= naxis <= MAX_NAXIS):
        raise _refuse(path, "NAXIS", naxis, f"it must be an integer from 0 to {MAX_NAXIS} (the number of axes)")
    for axis in range(1, naxis + 1):
        size = _value(header, f"NAXIS{axis}")
        if not (_is_int(size) and size >= 0):
            raise _refuse(path, f"NAXIS{axis}", size, f"with NAXIS = {naxis}, each of NAXIS1 to NAXIS{naxis} must be "
                          "an integer >= 0 (the length of that axis)")
    for key in ("BZERO", "BSCALE"):
        scale = _value(header, key)
        if scale is not _MISSING and not (is_real_number(scale) and math.isfinite(scale)):
            raise _refuse(path, key, scale, "it must be a finite number (it scales the stored pixel values)")
