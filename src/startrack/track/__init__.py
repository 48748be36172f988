"""Tracking: identify stars near where the last attitude and rate predict them, and the Tracker
state machine that chains frames (lost-in-space until it has an attitude, then tracking, back to
lost-in-space when tracking fails). DESIGN.md §1; Samaan 2002 Eq. 1–3, Jacobs 1995 §4, Huffman 2006 §8.2."""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "checked_rate": ".inputs",
    "RelativeMatch": ".relative",
    "rate_match": ".relative",
    "triangle_match": ".relative",
    "LOST_IN_SPACE": ".tracker",
    "TRACKING": ".tracker",
    "TrackStep": ".tracker",
    "Tracker": ".tracker",
    "TrackerOptions": ".tracker",
    "EXTRA_PREDICTED": ".windows",
    "WindowMatch": ".windows",
    "WindowMatcher": ".windows",
    "match_in_windows": ".windows",
    "one_to_one": ".windows",
    "project": ".windows",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
