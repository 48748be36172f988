"""Exceptions raised for misuse (bad arguments, unreadable files, corrupt data).

Expected failures of a solve (too few stars, no match) are *results* with a status, never
exceptions; see :mod:`startrack.results`.
"""

from __future__ import annotations


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
