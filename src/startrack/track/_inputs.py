"""The Tracker's checks of what a frame brings (star positions, fluxes, time, gyro rate, exposure):
finite numbers of the right shape, or an :class:`~startrack.errors.InvalidInputError` naming the
parameter."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError, as_float_array, checked_number
from ..rate import MAX_EXPOSURE_S, MIN_EXPOSURE_S


def checked_rate(rate_rad_s: ArrayLike, frame: str = "camera", name: str = "gyro_rate_rad_s") -> NDArray[np.float64]:
    """A rate (3,), rad/s in ``frame``, finite; the message names the argument ``name`` and the frame."""
    try:
        rate = np.array(rate_rad_s, dtype=float)
    except (TypeError, ValueError):
        rate = np.full(0, np.nan)
    if rate.shape != (3,) or not np.all(np.isfinite(rate)):
        raise InvalidInputError(f"{name} must be 3 finite numbers (rad/s, {frame} frame), got {rate_rad_s!r}")
    return rate


def checked_time(t_s: float) -> float:
    """The frame time as a float; NaN, an infinity or a non-number is refused."""
    try:
        value = float(t_s)
    except (TypeError, ValueError):
        raise InvalidInputError(f"t_s must be a finite number of seconds, got {t_s!r}") from None
    if not math.isfinite(value):
        raise InvalidInputError(f"t_s must be a finite number of seconds, got {t_s!r}")
    return value


def checked_stars(x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Star positions (N,) each, finite and of one shape (px)."""
    try:
        xs, ys = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError("x and y must be arrays of pixel positions (numbers)") from None
    if xs.ndim != 1 or xs.shape != ys.shape:
        raise InvalidInputError(f"x and y must be 1-D arrays of one length, got shapes {xs.shape} and {ys.shape}")
    for name, values in (("x", xs), ("y", ys)):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise InvalidInputError(f"{name} must hold finite pixel positions; entry {int(bad[0])} is "
                                    f"{values[bad[0]]!r} ({bad.size} not finite)")
    return xs, ys


def checked_flux(flux: ArrayLike, shape: tuple[int, ...]) -> NDArray[np.float64]:
    """Star fluxes of the stars' shape, finite."""
    values = as_float_array(flux, "flux")
    if values.shape != shape:
        raise InvalidInputError(f"flux must have one entry per star, shape {shape}, got {values.shape}")
    if not np.all(np.isfinite(values)):
        raise InvalidInputError("flux must be finite numbers (NaN or infinity given)")
    return values


def checked_exposure(exposure_s: object) -> float | None:
    """A frame's exposure time (s) as a float, or None; a number outside the exposures the streak
    rate is measured over (:data:`startrack.rate.MIN_EXPOSURE_S` to ``MAX_EXPOSURE_S``: 1 us to
    11.6 days), or anything that is not a number, is refused naming ``streak_exposure_s``."""
    if exposure_s is None:
        return None
    return checked_number(exposure_s, "streak_exposure_s (seconds, or None)", low=MIN_EXPOSURE_S, high=MAX_EXPOSURE_S)
