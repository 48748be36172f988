"""Exceptions raised for misuse (bad arguments, unreadable files, corrupt data).

Expected failures of a solve (too few stars, no match) are *results* with a status, never
exceptions; see :mod:`startrack.results`.
"""

from __future__ import annotations

from typing import TypeVar

_T = TypeVar("_T")


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
