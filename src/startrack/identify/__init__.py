"""Star identification: lost-in-space matching against the catalog (and, later, tracking).

The default lost-in-space matcher is :func:`match_lost_in_space` (four-star patterns with a
k-vector index per field-of-view scale, see :mod:`._quad_matcher`), backed by the pattern
database of :mod:`._database`. The other matchers, each with its options class and selectable by
name through :data:`MATCHERS` / :data:`OPTIONS` (``solve_stars(method=...)``):
:func:`match_pyramid`, :func:`match_angle_pivot`, :func:`match_triangles`, :func:`match_nvertex`,
:func:`match_van_bezooijen` (on the pair database of :mod:`._pair_database`) and
:func:`match_overlay` (with a prior attitude).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._angle_pivot import AnglePivotOptions, match_angle_pivot
    from ._candidate import Candidate, MatchOutcome
    from ._database import (
        DB_KIND,
        DB_VERSION,
        DatabaseSettings,
        PatternDatabase,
        database_report,
        is_cached,
        load_database,
    )
    from ._field_stars import FieldStars, field_stars
    from ._final_fit import REMATCH_RADIUS_PX, settle_matches
    from ._guided import GuidedStars, guided_stars, with_guided_stars
    from ._image_epoch import DEFAULT_EPOCH_JYEAR, epoch_from_header, epoch_jyear, parse_utc, resolve_epoch
    from ._image_fov import stated_fov_deg, stated_search_range
    from ._kvector import KVector
    from ._match_groups import (
        GroupProblem,
        VanBezooijenOptions,
        candidate_groups,
        match_pairs,
        match_van_bezooijen,
        region_mask,
        sub_catalogue,
    )
    from ._nvertex import NVertexOptions, match_nvertex
    from ._options_base import MatcherOptionsBase
    from ._overlay import OverlayOptions, match_overlay
    from ._pair_database import PairDatabase, PairSettings, load_pair_database
    from ._parity import PARITIES, Parity, check_parity, searched_mirrors, unmirrored
    from ._pyramid import PyramidOptions, candidate_triangles, match_pyramid, pyramid_triads
    from ._quad_matcher import MatcherOptions, match_lost_in_space
    from ._refine import pixel_vectors, refine_pointing, solution_terms
    from ._registry import (
        DEFAULT_FOV_RANGE_DEG,
        MATCHERS,
        OPTIONS,
        MethodName,
        check_method,
        check_options,
        database_settings_for,
        options_for,
        prepare_matcher,
    )
    from ._request import (
        FOV_DEG_TOLERANCE,
        MAX_FOV_DEG,
        MIN_FOV_DEG,
        SolveRequest,
        build_request,
        check_fov_deg,
        check_pixel_aspect,
        star_arrays,
    )
    from ._star_order import ordered_star_sets
    from ._triangles import TriangleOptions, match_triangles
    from ._verify import closest_pairs_first, match_nearest

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
