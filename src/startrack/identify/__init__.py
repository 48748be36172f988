"""Star identification: lost-in-space matching against the catalog (and, later, tracking).

The default lost-in-space matcher is :func:`match_lost_in_space` (four-star patterns with a
k-vector index per field-of-view scale, see :mod:`.quad_matcher`), backed by the pattern
database of :mod:`.database`.
"""

from __future__ import annotations

from .candidate import Candidate, MatchOutcome
from .database import DatabaseSettings, PatternDatabase, database_report, load_database
from .kvector import KVector
from .quad_matcher import MatcherOptions, match_lost_in_space

__all__ = [
    "Candidate",
    "DatabaseSettings",
    "KVector",
    "MatchOutcome",
    "MatcherOptions",
    "PatternDatabase",
    "database_report",
    "load_database",
    "match_lost_in_space",
]
