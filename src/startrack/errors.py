"""Exceptions raised for misuse (bad arguments, unreadable files, corrupt data).

Expected failures of a solve (too few stars, no match) are *results* with a status, never
exceptions; see :mod:`startrack.results`.
"""

from __future__ import annotations

import math
from numbers import Integral, Real
from typing import TYPE_CHECKING, Any, TypeVar, cast

if TYPE_CHECKING:  # numpy is imported where it is needed, not with this module
    import numpy as np

_T = TypeVar("_T")
_S = TypeVar("_S", bound=str)


class StartrackError(Exception):
    """Base class of every startrack exception."""


class InvalidInputError(StartrackError, ValueError):
    """An argument or an input array is not valid; the message says what would be."""


class ImageReadError(StartrackError, ValueError):
    """An image file is missing, empty, truncated or not an image."""


class CacheError(StartrackError):
    """A cache file could not be written."""


class OutputError(StartrackError, OSError):
    """An output could not be written (a full disk, no permission); the target was left unchanged."""


class CacheWarning(UserWarning):
    """The user cache could not be used (e.g. a read-only folder); startrack went on without it."""


def require(value: _T | None, what: str) -> _T:
    """``value`` itself when it is set: for a field a result fills only on success.

    A result's optional fields (an unsolved solution has no camera) are None only with a failure
    status; code that has checked the status reads them through this, so that a reader and a type
    checker both see the field cannot be None there. Raises RuntimeError naming ``what`` if it is:
    a broken invariant is a bug, not a user's input, so it is not a :class:`StartrackError` (which
    the CLI reports as a usage error) and it keeps its traceback.
    """
    if value is None:
        raise RuntimeError(f"{what} is not set (the result it belongs to did not succeed)")
    return value


def check_choice(value: object, choices: tuple[_S, ...], what: str) -> _S:
    """``value`` as the one of ``choices`` it equals (a ``Literal`` selector's names, from
    ``typing.get_args``); an InvalidInputError naming ``what``, the valid names and the value if none."""
    for choice in choices:
        if isinstance(value, str) and value == choice:  # not an array, whose == would be an array
            return choice
    raise InvalidInputError(f"{what} must be one of {', '.join(choices)}, got {value!r}")


def check_instance(value: object, cls: type[_T], what: str) -> _T:
    """``value`` itself when it is a ``cls``; an InvalidInputError naming ``what``, the class it must
    be and the class given if it is not (an options object of another stage or method)."""
    if not isinstance(value, cls):
        raise InvalidInputError(f"{what} must be a {public_name(cls)}, got a {type(value).__name__}")
    return value


def as_float_array(value: object, what: str) -> Any:
    """``numpy.asarray(value, dtype=float)``, or an InvalidInputError naming ``what`` when ``value`` does not
    hold numbers (a word, a dict, ragged lists) instead of numpy's ValueError or TypeError. Shape and
    finiteness are the caller's to check."""
    import numpy as np  # here: this module is imported before numpy is needed

    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} must be a number or an array of numbers, got {_short(value)}") from None


def checked_number(value: object, what: str, *, low: float = -math.inf, high: float = math.inf,
                   above_low: bool = False) -> float:
    """``value`` as a float when it is a real number (not a bool) in [low, high] (low excluded with
    ``above_low``; infinities and NaN never pass); else an InvalidInputError naming ``what``, the range
    and the value. For a function's scalar argument (:func:`check_positive` checks an object's fields)."""
    try:
        number = float(cast(float, value)) if is_real_number(value) else math.nan
    except OverflowError:  # an integer beyond float64
        number = math.inf
    inside = math.isfinite(number) and (number > low if above_low else number >= low) and number <= high
    if not inside:
        bounds = ("> " if above_low else ">= ") + f"{low:g}" if math.isfinite(low) else ""
        bounds = " and ".join(b for b in (bounds, f"<= {high:g}" if math.isfinite(high) else "") if b)
        raise InvalidInputError(f"{what} must be a finite number{' ' + bounds if bounds else ''}, got {_short(value)}")
    return number


def checked_count(value: object, what: str, low: int, high: int | None = None) -> int:
    """``value`` as an int when it is an integer (not a bool) in [low, high]; else an InvalidInputError
    naming ``what``, the range and the value."""
    if not (isinstance(value, Integral) and not isinstance(value, bool) and low <= int(value)
            and (high is None or int(value) <= high)):
        upper = "" if high is None else f" and <= {high}"
        raise InvalidInputError(f"{what} must be an integer >= {low}{upper}, got {_short(value)}")
    return int(value)


def checked_rng(rng: object) -> np.random.Generator:
    """``numpy.random.default_rng(rng)`` (a Generator); an InvalidInputError if ``rng`` is not one of what
    it takes (a Generator, a seed: an integer >= 0 or a sequence of them, or None)."""
    import numpy as np  # here: this module is imported before numpy is needed

    try:
        return np.random.default_rng(rng)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidInputError("rng must be a numpy Generator, a seed (an integer >= 0, or a sequence of them) "
                                f"or None, got {_short(rng)}") from None


def _short(value: object) -> str:
    """``repr(value)``, cut to 80 characters."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def is_real_number(value: object) -> bool:
    """Whether ``value`` is a real number (Python or numpy), not a bool."""
    return isinstance(value, Real) and not isinstance(value, bool)


def _or_none(optional: bool) -> str:
    return " or None" if optional else ""


def check_positive(obj: object, names: tuple[str, ...], optional: bool = False) -> None:
    """Each named attribute of ``obj`` (an options object) is a finite number > 0 (or None when
    ``optional``); else an InvalidInputError naming it."""
    for name in names:
        value = getattr(obj, name)
        if optional and value is None:
            continue
        if not (is_real_number(value) and math.isfinite(value) and value > 0):
            raise InvalidInputError(f"{name} must be a positive number{_or_none(optional)}, got {value!r}")


def check_non_negative(obj: object, names: tuple[str, ...]) -> None:
    """Each named attribute of ``obj`` is a finite number >= 0."""
    for name in names:
        value = getattr(obj, name)
        if not (is_real_number(value) and math.isfinite(value) and value >= 0):
            raise InvalidInputError(f"{name} must be a number >= 0, got {value!r}")


def check_finite(obj: object, names: tuple[str, ...]) -> None:
    """Each named attribute of ``obj`` is a finite number."""
    for name in names:
        value = getattr(obj, name)
        if not (is_real_number(value) and math.isfinite(value)):
            raise InvalidInputError(f"{name} must be a finite number, got {value!r}")


def check_int(obj: object, names: tuple[str, ...], minimum: int, optional: bool = False) -> None:
    """Each named attribute of ``obj`` is an integer >= ``minimum`` (or None when ``optional``)."""
    for name in names:
        value = getattr(obj, name)
        if optional and value is None:
            continue
        if not (isinstance(value, Integral) and not isinstance(value, bool) and int(value) >= minimum):
            raise InvalidInputError(f"{name} must be an integer >= {minimum}{_or_none(optional)}, got {value!r}")


def check_bool(obj: object, names: tuple[str, ...]) -> None:
    """Each named attribute of ``obj`` is True or False."""
    for name in names:
        value = getattr(obj, name)
        if not (isinstance(value, bool) or _is_numpy_bool(value)):
            raise InvalidInputError(f"{name} must be True or False, got {value!r}")


def _is_numpy_bool(value: object) -> bool:
    """Whether ``value`` is numpy's bool (``np.bool_``, named ``bool`` since numpy 2), told without
    importing numpy."""
    kind = type(value)
    return kind.__module__ == "numpy" and kind.__name__ in ("bool", "bool_")


def public_name(cls: type) -> str:
    """``cls`` by the name users import it under: its module's path up to the first private part
    (``startrack.rate._streak_solve.StreakOptions`` is ``startrack.rate.StreakOptions``)."""
    parts = cls.__module__.split(".")
    public = next((i for i, part in enumerate(parts) if part.startswith("_")), len(parts))
    return ".".join([*parts[:public], cls.__qualname__])


def hidden_interruption(exc: BaseException) -> BaseException | None:
    """The KeyboardInterrupt or SystemExit that ``exc`` stands for, if any (else None).

    A signal handler that raises (Ctrl-C's KeyboardInterrupt, the CLI's SIGTERM ``Terminated``)
    while compiled code runs comes back from it as ``SystemError: ... returned a result with an
    exception set``, an Exception whose cause or context is the interruption. A handler that
    turns any Exception into a result (a failed trial, a batch's error line) must re-raise it
    instead, or the process records a failure that never happened and carries on.
    """
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if not isinstance(current, Exception):
            return current
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return None
