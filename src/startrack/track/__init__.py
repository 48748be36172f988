"""Tracking: identify stars near where the last attitude and rate predict them, and the Tracker
state machine that chains frames (lost-in-space until it has an attitude, then tracking, back to
lost-in-space when tracking fails). DESIGN.md §1; Samaan 2002 Eq. 1–3, Jacobs 1995 §4, Huffman 2006 §8.2."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._inputs import checked_rate, checked_time
    from ._relative import RelativeMatch, rate_match, triangle_match
    from ._tracker import LOST_IN_SPACE, STEP_MODES, TRACKING, FrameMode, StepMode, Tracker, TrackerOptions, TrackStep
    from ._windows import EXTRA_PREDICTED, WindowMatch, WindowMatcher, match_in_windows, one_to_one, project

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
