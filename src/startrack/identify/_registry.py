"""Star-identification matchers by name: what ``startrack.solve_stars(method=...)`` runs.

Every matcher returns a :class:`.candidate.MatchOutcome` whose candidate has passed the same
confirmation (:mod:`._confirm`: a false-match probability below the threshold, 1e-6 by default).
Each entry of :data:`MATCHERS` is a function of the request that loads (or builds, once, into the
cache) the database the matcher needs, and returns the matcher and the catalog stars of the final
re-match. The table of what each needs and how fast it is lives in ``docs/identification.md``.

- ``quads`` (default): four-star patterns, any knowledge of the field of view (:mod:`._quad_matcher`).
- ``pyramid``, ``angle``, ``triangle-planar``, ``triangle-spherical``, ``nvertex-3``,
  ``nvertex-4``, ``nvertex-5``, ``van-bezooijen``: the seeds' matchers on the star-pair
  directory (:mod:`._pair_database`); they need the field of view to within 5 %.
- ``overlay``: the catalog overlaid with a prior attitude (Fowler 2013); needs a prior.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from functools import partial
from importlib import import_module
from typing import TYPE_CHECKING, Any, Literal, Protocol, TypeVar, get_args

from ..errors import InvalidInputError, check_choice, check_instance
from ._database import DB_MAX_FOV_DEG, DatabaseSettings
from ._options_base import MatcherOptionsBase

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray
    from scipy.spatial.transform import Rotation

    from ..camera import Camera
    from ._candidate import MatchOutcome
    from ._field_stars import FieldStars
    from ._parity import Parity

DEFAULT_FOV_RANGE_DEG: tuple[float, float] = (3.0, 100.0)
"""Searched when no field of view is given: telescopes' finder fields, star trackers, camera
lenses, phones and webcams (the range of the default pattern database)."""

WIDE_MIN_FOV_DEG = 70.0
"""A search whose range lies at or above this field (deg) and reaches past the default range (a wide
lens's field given, or an EXIF hint of one) is served by one database of the fields from here to
the widest (:data:`._database.DB_MAX_FOV_DEG`), built once, rather than one of its own for each
such range."""

NARROW_MAX_MAG = 12.5
"""A database reaching below the default range (fields under 3 deg, given with a hint or a
camera) takes every Hipparcos star (the catalog ends near V 12): a 1 deg field holds three of
them on average, and it needs four in a pattern and more to confirm it."""

PAIR_MAX_FOCAL_TOLERANCE = 0.05
"""The pair-directory matchers need the focal length to within this fraction."""

OVERLAY_MAX_MAG = 7.0
"""Faintest catalog star the overlay projects (about what a star tracker's frame shows)."""


MethodName = Literal["quads", "pyramid", "angle", "triangle-planar", "triangle-spherical", "nvertex-3",
                     "nvertex-4", "nvertex-5", "van-bezooijen", "overlay"]
"""The matchers' names (the keys of :data:`MATCHERS` and :data:`OPTIONS`; the module docstring)."""

METHOD_NAMES: tuple[MethodName, ...] = get_args(MethodName)
"""The names of :data:`MethodName`, in its order (what an unknown ``method`` is told to be)."""


class MatchRequest(Protocol):
    """What a matcher needs of a solve request (``startrack.solve``'s validated problem): read-only
    attributes, so that a frozen dataclass (:class:`.request.SolveRequest`) is one."""

    @property
    def x(self) -> NDArray[np.float64]: ...
    @property
    def y(self) -> NDArray[np.float64]: ...
    @property
    def camera(self) -> Camera: ...
    @property
    def focal_range(self) -> tuple[float, float] | None: ...
    @property
    def fov_range_deg(self) -> tuple[float, float]: ...
    @property
    def epoch_jyear(self) -> float: ...
    @property
    def prior_rot(self) -> Rotation | None: ...
    @property
    def prior_sigma_deg(self) -> float: ...
    @property
    def aspect_range(self) -> tuple[float, float] | None: ...
    @property
    def fit_aspect(self) -> bool: ...
    @property
    def parity(self) -> Parity: ...


Matcher = Callable[[MatcherOptionsBase | None], "MatchOutcome"]
"""A prepared matcher: called with its options (or None), returns the outcome."""

_O = TypeVar("_O", bound=MatcherOptionsBase)


def _own(options: MatcherOptionsBase | None, name: str, cls: type[_O]) -> _O | None:
    """``options`` as the ``name`` matcher's class ``cls`` (None stays None); another class is refused."""
    return None if options is None else check_instance(options, cls, f"options for the {name} matcher")


def database_settings_for(fov_range_deg: tuple[float, float] = DEFAULT_FOV_RANGE_DEG) -> DatabaseSettings:
    """Settings of the pattern database that serves this range of horizontal FOVs (degrees).

    The default database covers :data:`DEFAULT_FOV_RANGE_DEG`; a range reaching outside it
    gets a database of its own that covers just that range, 3 % wider on each side (built on
    first use; below 3 deg it takes every Hipparcos star, :data:`NARROW_MAX_MAG`, and still the
    stars thin out and so do the patterns), except a range of wide fields beyond the default's
    (:data:`WIDE_MIN_FOV_DEG`), which shares one.
    """
    lo, hi = fov_range_deg
    default = DatabaseSettings()
    if default.fov_min_deg <= lo and hi <= default.fov_max_deg:
        return default
    if lo >= WIDE_MIN_FOV_DEG:
        return DatabaseSettings(fov_min_deg=WIDE_MIN_FOV_DEG * 0.97, fov_max_deg=DB_MAX_FOV_DEG)
    max_mag = NARROW_MAX_MAG if lo < default.fov_min_deg else default.max_mag
    return DatabaseSettings(fov_min_deg=max(lo * 0.97, 0.4), fov_max_deg=min(hi * 1.03, DB_MAX_FOV_DEG),
                            max_mag=max_mag)


def _load(module: str, name: str):
    """``name`` from the module ``startrack.identify._<module>``, imported on first use (a matcher's
    modules are slow to import, so a call imports only those of the matcher it runs;
    ``benchmarks/startup_benchmark.py`` times the package's import)."""
    return getattr(import_module(f"._{module}", __package__), name)


def _quads(request: MatchRequest) -> tuple[Matcher, FieldStars]:
    from ._database import load_database
    from ._field_stars import field_stars
    from ._parity import searched_mirrors
    from ._quad_matcher import MatcherOptions, match_lost_in_space
    from ._quad_search import warm_up

    db = load_database(database_settings_for(request.fov_range_deg))
    warm_up(db)

    def run(options: MatcherOptionsBase | None) -> MatchOutcome:
        return match_lost_in_space(request.x, request.y, request.camera, db, request.focal_range,
                                   _own(options, "quads", MatcherOptions),
                                   aspect_range=request.aspect_range, fit_aspect=request.fit_aspect,
                                   mirrored=searched_mirrors(request.parity))

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


def _on_pairs(module: str, function: str, name: str, tables: Callable[[Any], object] | None = None,
              **keywords) -> Callable[[MatchRequest], tuple[Matcher, FieldStars]]:
    """Entry of a matcher with the signature of :func:`.pyramid.match_pyramid`: ``function`` of
    ``module`` with ``keywords``, imported when the entry is called; ``tables(pdb)`` loads (or
    builds) the other tables the matcher reads from the pair directory, before the solve's clock."""

    def prepare(request: MatchRequest) -> tuple[Matcher, FieldStars]:
        from ._field_stars import field_stars
        from ._pair_database import PairSettings, load_pair_database

        match = partial(_load(module, function), **keywords)
        camera, tolerance = _known_focal(request, name)
        settings = PairSettings(fov_deg=float(math.ceil(camera.fov_diagonal_deg * (1 + tolerance))))
        pdb = load_pair_database(settings)
        if tables is not None:
            tables(pdb)

        def run(options: MatcherOptionsBase | None) -> MatchOutcome:
            return match(request.x, request.y, camera, pdb, focal_tolerance=tolerance, options=options)

        return run, field_stars(settings.max_mag, request.epoch_jyear)

    return prepare


def _overlay(request: MatchRequest) -> tuple[Matcher, FieldStars]:
    from ._field_stars import field_stars
    from ._overlay import OverlayOptions, catalog_star_set, match_overlay
    from ._pair_database import PairSettings

    if request.prior_rot is None:
        raise InvalidInputError("the overlay matcher needs a prior attitude: give prior_rot_cam_from_icrs")
    camera, _ = _known_focal(request, "overlay")
    stars = catalog_star_set(OVERLAY_MAX_MAG, request.epoch_jyear)

    def run(options: MatcherOptionsBase | None) -> MatchOutcome:
        return match_overlay(request.x, request.y, camera, stars, request.prior_rot,
                             prior_sigma_deg=request.prior_sigma_deg,
                             options=_own(options, "overlay", OverlayOptions))

    return run, field_stars(PairSettings.max_mag, request.epoch_jyear)


def _triangle_directory(variant: str) -> Callable[[Any], object]:
    """The tables of the triangle matchers: a pair directory's triangle directory of ``variant``."""
    return lambda pdb: _load("triangle_database", "load_triangle_database")(pdb, variant)


MATCHERS: dict[MethodName, Callable[[MatchRequest], tuple[Matcher, FieldStars]]] = {
    "quads": _quads,
    "pyramid": _on_pairs("pyramid", "match_pyramid", "pyramid"),
    "angle": _on_pairs("angle_pivot", "match_angle_pivot", "angle"),
    "triangle-planar": _on_pairs("triangles", "match_triangles", "triangle-planar", _triangle_directory("planar"),
                                 variant="planar"),
    "triangle-spherical": _on_pairs("triangles", "match_triangles", "triangle-spherical",
                                    _triangle_directory("spherical"), variant="spherical"),
    "nvertex-3": _on_pairs("nvertex", "match_nvertex", "nvertex-3", n=3),
    "nvertex-4": _on_pairs("nvertex", "match_nvertex", "nvertex-4", n=4),
    "nvertex-5": _on_pairs("nvertex", "match_nvertex", "nvertex-5", n=5),
    "van-bezooijen": _on_pairs("match_groups", "match_van_bezooijen", "van-bezooijen"),
    "overlay": _overlay,
}
"""Matchers by name (see the module docstring); each imports its modules when it is called."""


class _Options(Mapping[str, type[MatcherOptionsBase]]):
    """The options dataclass of each matcher, imported when it is looked up."""

    _WHERE: dict[str, tuple[str, str]] = {
        "quads": ("quad_matcher", "MatcherOptions"), "pyramid": ("pyramid", "PyramidOptions"),
        "angle": ("angle_pivot", "AnglePivotOptions"),
        "triangle-planar": ("triangles", "TriangleOptions"), "triangle-spherical": ("triangles", "TriangleOptions"),
        "nvertex-3": ("nvertex", "NVertexOptions"), "nvertex-4": ("nvertex", "NVertexOptions"),
        "nvertex-5": ("nvertex", "NVertexOptions"), "van-bezooijen": ("match_groups", "VanBezooijenOptions"),
        "overlay": ("overlay", "OverlayOptions"),
    }

    def __getitem__(self, method: str) -> type[MatcherOptionsBase]:
        return _load(*self._WHERE[method])

    def __iter__(self) -> Iterator[str]:
        return iter(self._WHERE)

    def __len__(self) -> int:
        return len(self._WHERE)


OPTIONS: Mapping[str, type[MatcherOptionsBase]] = _Options()
"""The options dataclass of each matcher, a subclass of :class:`.options_base.MatcherOptionsBase`
(a read-only mapping; a look-up imports its module)."""


def check_method(method: str) -> MethodName:
    """``method`` as a :data:`MethodName`; an InvalidInputError naming the valid ones if it is not one."""
    return check_choice(method, METHOD_NAMES, "method")


def check_options(method: str, options: object) -> MethodName:
    """``method`` as a :data:`MethodName`, after checking that ``options`` (None or a dataclass)
    are that matcher's options class (:data:`OPTIONS`).

    Raises
    ------
    InvalidInputError
        For an unknown method (naming the valid ones), or options of another class (naming the
        method, the class given and the class it takes).
    """
    name = check_method(method)
    expected = OPTIONS[name]
    if options is not None and not isinstance(options, expected):
        raise InvalidInputError(f"options for the {name} matcher must be a {expected.__name__} "
                                f"(startrack.identify._registry.options_for({name!r}, ...)), "
                                f"got a {type(options).__name__}")
    return name


def options_for(method: str, **settings) -> MatcherOptionsBase:
    """The named matcher's options with some settings changed, e.g. ``options_for("pyramid", timeout_s=2)``."""
    method = check_method(method)
    try:
        return OPTIONS[method](**settings)
    except TypeError as exc:
        raise InvalidInputError(f"bad option for the {method} matcher: {exc}") from None


def prepare_matcher(method: MethodName | str, request: MatchRequest) -> tuple[Matcher, FieldStars]:
    """The named matcher, ready to run on the request, and the stars of the final re-match (their
    sky index made, :func:`.verify.bands_of`): what a solve loads or builds once is done here,
    before its clock starts, not in its reported time."""
    from ._verify import bands_of

    matcher, stars = MATCHERS[check_method(method)](request)
    bands_of(stars, stars.vectors)
    return matcher, stars


__all__ = ["DEFAULT_FOV_RANGE_DEG", "MATCHERS", "METHOD_NAMES", "OPTIONS", "MatchRequest", "MethodName",
           "check_method", "check_options", "database_settings_for", "options_for", "prepare_matcher"]
