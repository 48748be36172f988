"""Star identification: lost-in-space matching against the catalog (and, later, tracking).

The default lost-in-space matcher is :func:`match_lost_in_space` (four-star patterns with a
k-vector index per field-of-view scale, see :mod:`.quad_matcher`), backed by the pattern
database of :mod:`.database`.
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "Candidate": ".candidate",
    "MatchOutcome": ".candidate",
    "DatabaseSettings": ".database",
    "PatternDatabase": ".database",
    "database_report": ".database",
    "load_database": ".database",
    "KVector": ".kvector",
    "MatcherOptions": ".quad_matcher",
    "match_lost_in_space": ".quad_matcher",
}

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

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
