"""Star-identification matchers by name: what ``startrack.solve_stars(method=...)`` runs.

Every matcher returns a :class:`.candidate.MatchOutcome` whose candidate has passed the same
confirmation (:mod:`.confirm`: a false-match probability below the threshold, 1e-6 by default).
Each entry of :data:`MATCHERS` is a function of the request that loads (or builds, once, into the
cache) the database the matcher needs, and returns the matcher and the catalog stars of the final
re-match. The table of what each needs and how fast it is lives in ``docs/identification.md``.

- ``quads`` (default): four-star patterns, any knowledge of the field of view (:mod:`.quad_matcher`).
- ``pyramid``, ``angle``, ``triangle-planar``, ``triangle-spherical``, ``nvertex-3``,
  ``nvertex-4``, ``nvertex-5``, ``van-bezooijen``: the seeds' matchers on the star-pair
  directory (:mod:`.pair_database`); they need the field of view to within 5 %.
- ``overlay``: the catalog overlaid with a prior attitude (seed 003); needs a prior.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from typing import Protocol

from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError
from .angle_pivot import AnglePivotOptions, match_angle_pivot
from .candidate import MatchOutcome
from .database import DB_MAX_FOV_DEG, DatabaseSettings, load_database
from .field_stars import FieldStars, field_stars
from .match_groups import VanBezooijenOptions, match_van_bezooijen
from .nvertex import NVertexOptions, match_nvertex
from .overlay import OverlayOptions, catalog_star_set, match_overlay
from .pair_database import PairSettings, load_pair_database
from .pyramid import PyramidOptions, match_pyramid
from .quad_matcher import MatcherOptions, match_lost_in_space
from .quad_search import warm_up
from .triangles import TriangleOptions, match_triangles

DEFAULT_FOV_RANGE_DEG: tuple[float, float] = (3.0, 100.0)
"""Searched when no field of view is given: telescopes' finder fields, star trackers, camera
lenses, phones and webcams (the range of the default pattern database)."""

NARROW_MAX_MAG = 12.5
"""A database reaching below the default range (fields under 3 deg, given with a hint or a
camera) takes every Hipparcos star (the catalog ends near V 12): a 1 deg field holds three of
them on average, and it needs four in a pattern and more to confirm it."""

PAIR_MAX_FOCAL_TOLERANCE = 0.05
"""The pair-directory matchers need the focal length to within this fraction."""

OVERLAY_MAX_MAG = 7.0
"""Faintest catalog star the overlay projects (about what a star tracker's frame shows)."""


class MatchRequest(Protocol):
    """What a matcher needs of a solve request (``startrack.solve``'s validated problem)."""

    x: object
    y: object
    camera: Camera
    focal_range: tuple[float, float] | None
    fov_range_deg: tuple[float, float]
    epoch_jyear: float
    prior_rot: Rotation | None
    prior_sigma_deg: float
    aspect_range: tuple[float, float] | None
    fit_aspect: bool


Matcher = Callable[[object | None], MatchOutcome]
"""A prepared matcher: called with its options (or None), returns the outcome."""


def database_settings_for(fov_range_deg: tuple[float, float] = DEFAULT_FOV_RANGE_DEG) -> DatabaseSettings:
    """Settings of the pattern database that serves this range of horizontal FOVs (degrees).

    The default database covers :data:`DEFAULT_FOV_RANGE_DEG`; a range reaching outside it
    gets a database of its own that covers just that range, 3 % wider on each side (built on
    first use; below 3 deg it takes every Hipparcos star, :data:`NARROW_MAX_MAG`, and still the
    stars thin out and so do the patterns).
    """
    lo, hi = fov_range_deg
    default = DatabaseSettings()
    if default.fov_min_deg <= lo and hi <= default.fov_max_deg:
        return default
    depth = {"max_mag": NARROW_MAX_MAG} if lo < default.fov_min_deg else {}
    return DatabaseSettings(fov_min_deg=max(lo * 0.97, 0.4), fov_max_deg=min(hi * 1.03, DB_MAX_FOV_DEG), **depth)


def _quads(request: MatchRequest) -> tuple[Matcher, FieldStars]:
    db = load_database(database_settings_for(request.fov_range_deg))
    warm_up(db)

    def run(options):
        return match_lost_in_space(request.x, request.y, request.camera, db, request.focal_range, options,
                                   aspect_range=request.aspect_range, fit_aspect=request.fit_aspect)

    return run, field_stars(db.settings.max_mag, request.epoch_jyear)


def _known_focal(request: MatchRequest, name: str) -> tuple[Camera, float]:
    """The camera at the middle of the focal range, and the range's relative half-width."""
    if request.aspect_range is not None:
        raise InvalidInputError(f"the {name} matcher needs the pixel aspect: give pixel_aspect as one number "
                                "(or use method='quads' to search a range)")
    lo, hi = request.focal_range or (request.camera.fx, request.camera.fx)
    tolerance = (hi / lo - 1.0) / 2.0
    if tolerance > PAIR_MAX_FOCAL_TOLERANCE:
        raise InvalidInputError(f"the {name} matcher needs the field of view to within 5 %: give fov_deg or a "
                                "camera (or use method='quads' with a FOV range)")
    camera = request.camera.with_focal(math.sqrt(lo * hi)) if request.focal_range else request.camera
    return camera, tolerance


def _on_pairs(match: Callable[..., MatchOutcome], name: str) -> Callable[[MatchRequest], tuple[Matcher, FieldStars]]:
    """Entry of a matcher with the signature of :func:`.pyramid.match_pyramid`."""

    def prepare(request: MatchRequest) -> tuple[Matcher, FieldStars]:
        camera, tolerance = _known_focal(request, name)
        settings = PairSettings(fov_deg=float(math.ceil(camera.fov_diagonal_deg * (1 + tolerance))))
        pdb = load_pair_database(settings)

        def run(options):
            return match(request.x, request.y, camera, pdb, focal_tolerance=tolerance, options=options)

        return run, field_stars(settings.max_mag, request.epoch_jyear)

    return prepare


def _overlay(request: MatchRequest) -> tuple[Matcher, FieldStars]:
    if request.prior_rot is None:
        raise InvalidInputError("the overlay matcher needs a prior attitude: give prior_rot_cam_from_icrs")
    camera, _ = _known_focal(request, "overlay")
    stars = catalog_star_set(OVERLAY_MAX_MAG, request.epoch_jyear)

    def run(options):
        return match_overlay(request.x, request.y, camera, stars, request.prior_rot,
                             prior_sigma_deg=request.prior_sigma_deg, options=options)

    return run, field_stars(PairSettings.max_mag, request.epoch_jyear)


MATCHERS: dict[str, Callable[[MatchRequest], tuple[Matcher, FieldStars]]] = {
    "quads": _quads,
    "pyramid": _on_pairs(match_pyramid, "pyramid"),
    "angle": _on_pairs(match_angle_pivot, "angle"),
    "triangle-planar": _on_pairs(partial(match_triangles, variant="planar"), "triangle-planar"),
    "triangle-spherical": _on_pairs(partial(match_triangles, variant="spherical"), "triangle-spherical"),
    "nvertex-3": _on_pairs(partial(match_nvertex, n=3), "nvertex-3"),
    "nvertex-4": _on_pairs(partial(match_nvertex, n=4), "nvertex-4"),
    "nvertex-5": _on_pairs(partial(match_nvertex, n=5), "nvertex-5"),
    "van-bezooijen": _on_pairs(match_van_bezooijen, "van-bezooijen"),
    "overlay": _overlay,
}
"""Matchers by name (see the module docstring)."""


OPTIONS: dict[str, type] = {
    "quads": MatcherOptions, "pyramid": PyramidOptions, "angle": AnglePivotOptions,
    "triangle-planar": TriangleOptions, "triangle-spherical": TriangleOptions,
    "nvertex-3": NVertexOptions, "nvertex-4": NVertexOptions, "nvertex-5": NVertexOptions,
    "van-bezooijen": VanBezooijenOptions, "overlay": OverlayOptions,
}
"""The options dataclass of each matcher."""


def options_for(method: str, **settings) -> object:
    """The named matcher's options with some settings changed, e.g. ``options_for("pyramid", timeout_s=2)``."""
    if method not in OPTIONS:
        raise InvalidInputError(f"method must be one of {', '.join(OPTIONS)}, got {method!r}")
    try:
        return OPTIONS[method](**settings)
    except TypeError as exc:
        raise InvalidInputError(f"bad option for the {method} matcher: {exc}") from None


def prepare_matcher(method: str, request: MatchRequest) -> tuple[Matcher, FieldStars]:
    """The named matcher, ready to run on the request, and the stars of the final re-match."""
    if method not in MATCHERS:
        raise InvalidInputError(f"method must be one of {', '.join(MATCHERS)}, got {method!r}")
    return MATCHERS[method](request)


__all__ = ["DEFAULT_FOV_RANGE_DEG", "MATCHERS", "OPTIONS", "MatchRequest", "database_settings_for", "options_for",
           "prepare_matcher"]
