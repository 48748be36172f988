"""Tracking: identify stars near where the last attitude and rate predict them, and the Tracker
state machine that chains frames (lost-in-space until it has an attitude, then tracking, back to
lost-in-space when tracking fails). DESIGN.md §1; seed 004 §2.2, seed 002 §4, seed 000 §8.2."""

from __future__ import annotations

from .relative import RelativeMatch, rate_match, triangle_match
from .tracker import Tracker, TrackerOptions, TrackStep
from .windows import WindowMatch, match_in_windows

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
