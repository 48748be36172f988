"""The base class of every matcher's options (issue 21 item 2: one options class per stage).

Each matcher of :mod:`._registry` takes its own frozen dataclass of settings, a subclass of
:class:`MatcherOptionsBase`, which holds the settings they all share: how the final candidate is
confirmed (:mod:`._confirm`). ``startrack.solve_stars`` refuses options of another matcher's class
(:func:`.registry.check_options`). This module imports nothing heavy: the registry loads it
without loading any matcher.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MatcherOptionsBase:
    """Settings every matcher shares: the confirmation of its candidate (:mod:`._confirm`).

    Attributes
    ----------
    verify_stars : int
        Brightest image stars tested against the predicted catalog stars.
    match_radius_px : float or None
        Confirmation radius (pixels); None: :func:`.confirm.match_radius_px`'s default for the
        image size.
    max_false_match_prob : float
        A match is accepted only when its false-match probability bound is below this.
    """

    verify_stars: int = 40
    match_radius_px: float | None = None
    max_false_match_prob: float = 1e-6


__all__ = ["MatcherOptionsBase"]
