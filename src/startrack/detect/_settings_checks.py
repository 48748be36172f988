"""Validation of detector settings: each check raises InvalidInputError naming the setting (the
generic number checks are :mod:`startrack.errors`'; these are the detector's own)."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidInputError, is_real_number


def check_choice(obj, name: str, choices: tuple[str, ...]) -> None:
    """The named attribute is one of ``choices``."""
    value = getattr(obj, name)
    if not (isinstance(value, str) and value in choices):
        raise InvalidInputError(f"{name} must be one of {choices}, got {value!r}")


def check_pair(obj, name: str, optional: bool, integer: bool) -> None:
    """The named attribute is a pair of finite numbers (integers >= 0 when ``integer``)."""
    value = getattr(obj, name)
    if optional and value is None:
        return
    ok = isinstance(value, tuple | list) and len(value) == 2 and all(is_real_number(v) for v in value)
    if ok and integer:
        ok = all(isinstance(v, int | np.integer) and v >= 0 for v in value)
    if ok:
        ok = all(math.isfinite(v) for v in value)
    if not ok:
        kind = "two integers >= 0" if integer else "two finite numbers (dx, dy)"
        raise InvalidInputError(f"{name} must be {kind}{' or None' if optional else ''}, got {value!r}")


def check_dark(value) -> None:
    """A dark frame is None or a 2-D (or colour 3-D) numeric array."""
    if value is None:
        return
    array = np.asarray(value)
    numeric = np.issubdtype(array.dtype, np.integer) or np.issubdtype(array.dtype, np.floating)
    if not (numeric and array.ndim in (2, 3)):
        raise InvalidInputError(
            f"dark_frame must be a 2-D numeric array of the image's shape or None, got "
            f"{array.dtype} array of shape {array.shape}")
