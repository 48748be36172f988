"""Exceptions raised for misuse (bad arguments, unreadable files, corrupt data).

Expected failures of a solve (too few stars, no match) are *results* with a status, never
exceptions; see :mod:`startrack.results`.
"""

from __future__ import annotations

from typing import TypeVar

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
        if value == choice:
            return choice
    raise InvalidInputError(f"{what} must be one of {', '.join(choices)}, got {value!r}")


def check_instance(value: object, cls: type[_T], what: str) -> _T:
    """``value`` itself when it is a ``cls``; an InvalidInputError naming ``what``, the class it must
    be and the class given if it is not (an options object of another stage or method)."""
    if not isinstance(value, cls):
        raise InvalidInputError(f"{what} must be a {public_name(cls)}, got a {type(value).__name__}")
    return value


def public_name(cls: type) -> str:
    """``cls`` by the name users import it under: its module's path up to the first private part
    (``startrack.rate._streak_solve.StreakOptions`` is ``startrack.rate.StreakOptions``)."""
    parts = cls.__module__.split(".")
    public = next((i for i, part in enumerate(parts) if part.startswith("_")), len(parts))
    return ".".join([*parts[:public], cls.__qualname__])
