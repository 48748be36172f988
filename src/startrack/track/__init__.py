"""Tracking: identify stars near where the last attitude and rate predict them, and the Tracker
state machine that chains frames (lost-in-space until it has an attitude, then tracking, back to
lost-in-space when tracking fails). DESIGN.md §1; seed 004 §2.2, seed 002 §4, seed 000 §8.2."""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "RelativeMatch": ".relative",
    "rate_match": ".relative",
    "triangle_match": ".relative",
    "Tracker": ".tracker",
    "TrackerOptions": ".tracker",
    "TrackStep": ".tracker",
    "WindowMatch": ".windows",
    "match_in_windows": ".windows",
}

__all__ = [
    "RelativeMatch",
    "TrackStep",
    "Tracker",
    "TrackerOptions",
    "WindowMatch",
    "match_in_windows",
    "rate_match",
    "triangle_match",
]

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
