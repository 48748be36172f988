"""The catalog epoch of a solve: given, read from the image's header, or the default J2000.0.

Star positions move (proper motion: up to 10 arcsec a year for the fastest Hipparcos stars, and
tens of arcseconds over the 26 years since J2000.0 for a few hundred of them), so a photo is best
solved against the catalog at the time it was taken. The time comes, in this order, from:

1. ``CATEPOCH``: the catalog epoch (Julian year) startrack's simulator rendered a FITS frame at;
2. ``DATE-OBS``: FITS start of the exposure, UTC, ISO 8601 (a date-only value takes ``TIME-OBS``
   or ``UT``, as :func:`startrack.calibrate._ground.time_from_header` reads it);
3. ``MJD-OBS``: FITS start of the exposure as a modified Julian date (UTC);
4. ``DateTimeOriginal``: EXIF capture time, with ``OffsetTimeOriginal`` when the camera wrote it,
   else taken as UTC: a camera clock's zone moves the epoch by at most 14 h, 0.0016 yr, a
   millionth of an arcsecond of proper motion for most stars.

A FITS time that cannot be read is refused (the header says something wrong about the image;
``epoch=`` overrides it); an EXIF time that cannot be read (cameras write ``0000:00:00 00:00:00``
when their clock was never set) is passed over, as the EXIF reader passes over a broken block.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..catalog import EPOCH_RANGE_JYEAR, jyear_tdb
from ..catalog import epoch_jyear as catalog_epoch_jyear
from ..errors import InvalidInputError

if TYPE_CHECKING:
    from astropy.time import Time

DEFAULT_EPOCH_JYEAR = 2000.0
"""The catalog epoch when nothing says when the image was taken."""


J2000_MJD = 51544.5
"""Modified Julian date of J2000.0."""


@dataclass(frozen=True)
class Epoch:
    """A catalog epoch and where it came from.

    Attributes
    ----------
    jyear : float
        Julian year (TDB), e.g. 2024.6.
    source : str
        ``"given"``, a header key (``"CATEPOCH"``, ``"DATE-OBS"``, ``"MJD-OBS"``,
        ``"DateTimeOriginal"``) or ``"default"`` (J2000.0: nothing said when).
    """

    jyear: float
    source: str


def epoch_jyear(epoch: Time | float | None) -> float:
    """A catalog epoch as a Julian year (TDB): None gives J2000.0; accepts astropy Time or a year.

    :func:`startrack.catalog.epoch_jyear` (the one converter) with None as the default epoch.

    Raises
    ------
    InvalidInputError
        For a year outside 1000-3000, a non-number, or a Time that is not a single instant.
    """
    return DEFAULT_EPOCH_JYEAR if epoch is None else catalog_epoch_jyear(epoch)


def parse_utc(text: str, name: str = "time") -> Time:
    """An ISO 8601 UTC time (``2024-08-12T03:15:00``, a date, or with a space for the T), or an
    InvalidInputError naming ``name`` and what would be valid."""
    from astropy.time import Time
    from erfa import ErfaWarning

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ErfaWarning)
            when = Time(str(text).strip(), scale="utc")
        jyear = jyear_tdb(when)
    except (ValueError, TypeError):
        raise InvalidInputError(f"{name} must be an ISO 8601 UTC time such as 2024-08-12T03:15:00, "
                                f"got {text!r}") from None
    lo, hi = EPOCH_RANGE_JYEAR
    if not (when.isscalar and lo < jyear < hi):
        raise InvalidInputError(f"{name} must be one ISO 8601 UTC time between the years {lo:g} and {hi:g}, "
                                f"got {text!r}")
    return when


def epoch_from_header(header: Mapping[str, Any]) -> Epoch | None:
    """The epoch an image header states (module docstring for the order), or None.

    Raises
    ------
    InvalidInputError
        When ``CATEPOCH``, ``DATE-OBS`` or ``MJD-OBS`` is present but cannot be read, naming the
        card and the value.
    """
    if "CATEPOCH" in header:
        return Epoch(_card_number(header, "CATEPOCH", "a Julian year"), "CATEPOCH")
    if "DATE-OBS" in header:
        return Epoch(_header_time(header, "DATE-OBS"), "DATE-OBS")
    if "MJD-OBS" in header:
        mjd = _card_number(header, "MJD-OBS", "a modified Julian date")
        lo, hi = EPOCH_RANGE_JYEAR
        jyear = 2000.0 + (mjd - J2000_MJD) / 365.25  # near enough to refuse a date ERFA cannot take
        if not lo < jyear < hi:
            raise InvalidInputError(f"the image header's MJD-OBS = {mjd!r} is not a modified Julian date "
                                    f"between the years {lo:g} and {hi:g}; give the epoch to override it")
        from astropy.time import Time

        return Epoch(jyear_tdb(Time(mjd, format="mjd", scale="utc")), "MJD-OBS")
    if "DateTimeOriginal" in header:
        try:
            return Epoch(_header_time(header, "DateTimeOriginal"), "DateTimeOriginal")
        except InvalidInputError:
            return None  # an unset camera clock: passed over, as broken EXIF is
    return None


def resolve_epoch(epoch, header: Mapping[str, Any] | None = None) -> Epoch:
    """The epoch of a solve: ``epoch`` when given (a Time or a Julian year), else the header's
    (:func:`epoch_from_header`), else J2000.0."""
    if epoch is not None:
        return Epoch(epoch_jyear(epoch), "given")
    found = epoch_from_header(header or {})
    return found if found is not None else Epoch(DEFAULT_EPOCH_JYEAR, "default")


def _card_number(header: Mapping[str, Any], key: str, what: str) -> float:
    value = header[key]
    try:
        number = float(value) if not isinstance(value, bool | str) else float(str(value).strip())
    except (TypeError, ValueError):
        number = math.nan
    if not math.isfinite(number):
        raise InvalidInputError(f"the image header's {key} = {value!r} is not {what}; "
                                "give the epoch to override it")
    return catalog_epoch_jyear(number, f"the epoch in the image header's {key}") if key == "CATEPOCH" else number


def _header_time(header: Mapping[str, Any], key: str) -> float:
    """The Julian year of a DATE-OBS (with TIME-OBS / UT) or EXIF DateTimeOriginal (with its
    zone, else as UTC), read by :func:`startrack.calibrate._ground.time_from_header`."""
    from erfa import ErfaWarning

    from ..calibrate import time_from_header

    names = ("DATE-OBS", "TIME-OBS", "UT") if key == "DATE-OBS" else (
        "DateTimeOriginal", "SubsecTimeOriginal", "OffsetTimeOriginal")
    cards = {name: header[name] for name in names if name in header}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ErfaWarning)
            when = time_from_header(cards, utc_offset_hours=0.0, mid_exposure=False)
    except (InvalidInputError, ValueError) as exc:
        raise InvalidInputError(f"the image header's {key} = {header[key]!r} is not a time ({exc}); "
                                "give the epoch to override it") from None
    return catalog_epoch_jyear(jyear_tdb(when), f"the epoch from the image header's {key}")
