"""The catalog epoch as a Julian year (TDB): the one converter of startrack.

Star positions are given at an epoch (:meth:`StarCatalog.vectors`, the simulator's sky, a solve's
catalog); every epoch a user passes, an astropy ``Time`` or a Julian year, becomes a float here.
The module imports neither numpy nor astropy (a ``Time`` can exist only once ``astropy.time`` is
loaded), so a command that is given a year pays for neither; that is why it lives here and not in
:mod:`startrack.frames`, which loads numpy and scipy's rotations.
"""

from __future__ import annotations

import math
import sys
import warnings
from typing import TYPE_CHECKING

from ..errors import InvalidInputError

if TYPE_CHECKING:
    from astropy.time import Time

EPOCH_RANGE_JYEAR = (1000.0, 3000.0)
"""Epochs outside this range (exclusive, Julian years) are refused as mistakes."""


def jyear_tdb(when: Time) -> float:
    """Julian year (TDB) of a scalar astropy ``Time``, unchecked.

    ERFA's warnings (a UTC year outside the leap-second table, before 1960 or far ahead) are
    silenced: unknown leap seconds move an epoch by seconds, about a micro-arcsecond of motion even
    for Barnard's star.
    """
    from erfa import ErfaWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ErfaWarning)
        return float(when.tdb.jyear)


def epoch_jyear(epoch: Time | float, name: str = "epoch") -> float:
    """An epoch as a Julian year (TDB): an astropy ``Time`` via :func:`jyear_tdb`, a number as is.

    The one epoch converter of startrack (module docstring). ``name`` is the caller's parameter,
    named in the error.

    Raises
    ------
    InvalidInputError
        Naming ``name``: for a Time that is not a single instant, a bool, a string, a non-number,
        or a year outside :data:`EPOCH_RANGE_JYEAR`.
    """
    time_module = sys.modules.get("astropy.time")
    if time_module is not None and isinstance(epoch, time_module.Time):
        if not epoch.isscalar:
            raise InvalidInputError(f"{name} must be a single time, got an array of {epoch.size}")
        return _checked_jyear(jyear_tdb(epoch), epoch, name)
    what = f"{name} must be an astropy Time or a Julian year such as 2025.5"
    if isinstance(epoch, bool | str):
        raise InvalidInputError(f"{what}, got {epoch!r}")
    try:
        value = float(epoch)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what}, got {epoch!r}") from None
    return _checked_jyear(value, epoch, name)


def _checked_jyear(value: float, given: object, name: str) -> float:
    lo, hi = EPOCH_RANGE_JYEAR
    if not (math.isfinite(value) and lo < value < hi):
        raise InvalidInputError(f"{name} must be an astropy Time or a Julian year such as 2025.5 "
                                f"(between {lo:g} and {hi:g}), got {given!r}")
    return value
