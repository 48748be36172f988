"""Validation of detector settings: each check raises InvalidInputError naming the setting."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidInputError


def _or_none(optional: bool) -> str:
    return " or None" if optional else ""


def _is_number(value) -> bool:
    return isinstance(value, int | float | np.number) and not isinstance(value, bool | np.bool_)


def check_positive(obj, names: tuple[str, ...], optional: bool = False) -> None:
    """Each named attribute is a finite number > 0 (or None when ``optional``)."""
    for name in names:
        value = getattr(obj, name)
        if optional and value is None:
            continue
        if not (_is_number(value) and math.isfinite(value) and value > 0):
            raise InvalidInputError(
                f"{name} must be a positive number{_or_none(optional)}, got {value!r}")


def check_non_negative(obj, names: tuple[str, ...]) -> None:
    """Each named attribute is a finite number >= 0."""
    for name in names:
        value = getattr(obj, name)
        if not (_is_number(value) and math.isfinite(value) and value >= 0):
            raise InvalidInputError(f"{name} must be a number >= 0, got {value!r}")


def check_int(obj, names: tuple[str, ...], minimum: int, optional: bool = False) -> None:
    """Each named attribute is an integer >= ``minimum`` (or None when ``optional``)."""
    for name in names:
        value = getattr(obj, name)
        if optional and value is None:
            continue
        is_int = isinstance(value, int | np.integer) and not isinstance(value, bool)
        if not (is_int and value >= minimum):
            raise InvalidInputError(
                f"{name} must be an integer >= {minimum}{_or_none(optional)}, got {value!r}")


def check_choice(obj, name: str, choices: tuple[str, ...]) -> None:
    """The named attribute is one of ``choices``."""
    value = getattr(obj, name)
    if not (isinstance(value, str) and value in choices):
        raise InvalidInputError(f"{name} must be one of {choices}, got {value!r}")


def check_bool(obj, names: tuple[str, ...]) -> None:
    for name in names:
        if not isinstance(getattr(obj, name), bool | np.bool_):
            raise InvalidInputError(f"{name} must be True or False, got {getattr(obj, name)!r}")


def check_pair(obj, name: str, optional: bool, integer: bool) -> None:
    """The named attribute is a pair of finite numbers (integers >= 0 when ``integer``)."""
    value = getattr(obj, name)
    if optional and value is None:
        return
    ok = isinstance(value, tuple | list) and len(value) == 2 and all(_is_number(v) for v in value)
    if ok and integer:
        ok = all(isinstance(v, int | np.integer) and v >= 0 for v in value)
    if ok:
        ok = all(math.isfinite(v) for v in value)
    if not ok:
        kind = "two integers >= 0" if integer else "two finite numbers (dx, dy)"
        raise InvalidInputError(f"{name} must be {kind}{_or_none(optional)}, got {value!r}")


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
