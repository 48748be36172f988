"""Star identification: lost-in-space matching against the catalog (and, later, tracking).

The default lost-in-space matcher is :func:`match_lost_in_space` (four-star patterns with a
k-vector index per field-of-view scale, see :mod:`.quad_matcher`), backed by the pattern
database of :mod:`.database`. The other matchers, each with its options class and selectable by
name through :data:`MATCHERS` / :data:`OPTIONS` (``solve_stars(method=...)``):
:func:`match_pyramid`, :func:`match_angle_pivot`, :func:`match_triangles`, :func:`match_nvertex`,
:func:`match_van_bezooijen` (on the pair database of :mod:`.pair_database`) and
:func:`match_overlay` (with a prior attitude).
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "AnglePivotOptions": ".angle_pivot",
    "match_angle_pivot": ".angle_pivot",
    "Candidate": ".candidate",
    "MatchOutcome": ".candidate",
    "DB_KIND": ".database",
    "DB_VERSION": ".database",
    "DatabaseSettings": ".database",
    "PatternDatabase": ".database",
    "database_report": ".database",
    "is_cached": ".database",
    "load_database": ".database",
    "FieldStars": ".field_stars",
    "settle_matches": ".final_fit",
    "DEFAULT_EPOCH_JYEAR": ".image_epoch",
    "epoch_from_header": ".image_epoch",
    "epoch_jyear": ".image_epoch",
    "parse_utc": ".image_epoch",
    "resolve_epoch": ".image_epoch",
    "KVector": ".kvector",
    "GroupProblem": ".match_groups",
    "VanBezooijenOptions": ".match_groups",
    "candidate_groups": ".match_groups",
    "match_pairs": ".match_groups",
    "match_van_bezooijen": ".match_groups",
    "region_mask": ".match_groups",
    "sub_catalogue": ".match_groups",
    "NVertexOptions": ".nvertex",
    "match_nvertex": ".nvertex",
    "OverlayOptions": ".overlay",
    "match_overlay": ".overlay",
    "PairDatabase": ".pair_database",
    "PairSettings": ".pair_database",
    "load_pair_database": ".pair_database",
    "PyramidOptions": ".pyramid",
    "candidate_triangles": ".pyramid",
    "match_pyramid": ".pyramid",
    "pyramid_triads": ".pyramid",
    "MatcherOptions": ".quad_matcher",
    "match_lost_in_space": ".quad_matcher",
    "pixel_vectors": ".refine",
    "refine_pointing": ".refine",
    "solution_terms": ".refine",
    "DEFAULT_FOV_RANGE_DEG": ".registry",
    "MATCHERS": ".registry",
    "OPTIONS": ".registry",
    "database_settings_for": ".registry",
    "options_for": ".registry",
    "prepare_matcher": ".registry",
    "FOV_DEG_TOLERANCE": ".request",
    "SolveRequest": ".request",
    "build_request": ".request",
    "check_fov_deg": ".request",
    "check_pixel_aspect": ".request",
    "star_arrays": ".request",
    "ordered_star_sets": ".star_order",
    "TriangleOptions": ".triangles",
    "match_triangles": ".triangles",
    "closest_pairs_first": ".verify",
    "match_nearest": ".verify",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
