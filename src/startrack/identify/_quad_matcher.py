"""Lost-in-space identification by four-star patterns, with an unknown or known focal length.

The default matcher. Steps (after tetra3's pattern hashing, with a sorted key index over all scales):

1. Form four-star patterns from the brightest image stars, brightest combinations first, in
   batches (:func:`pattern_batches`); steps 2-4 run on a whole batch at once
   (:mod:`._quad_search`).
2. For each, the image vectors depend on the focal length; when it is only known as a range,
   choose the few trial focal lengths that change the pattern's edge ratios by more than the
   tolerance. Wide fields need several, narrow fields one.
3. Look the ratios up in the levels of the database whose scale fits the trial field of view:
   key ranges on a key of the three smallest ratios, then all five ratios, then the scale.
4. For each candidate, take the star correspondence whose edges agree best, correct the focal
   length from the edge sums, fit the rotation (q-method) and check the residuals.
5. Verify against the level's verification stars and bound the false-match probability
   (:mod:`._confirm`, :mod:`._verify`); the first candidate below the threshold wins.
6. (In :mod:`startrack.solve`) refine attitude and focal length on all matched stars (:mod:`._refine`).

When no pattern of a list with fewer stars than one pattern pool (``pattern_stars``, 20) verifies,
steps 3-5 run once more with the window of levels one level wider each way (step 3 keeps the
levels within the level ratio of the field of view, which suits a list with the stars of the
field; a list of only its few brightest, six say, has patterns that the levels of the next wider
field hold, and a field of view given exactly left those out: 15 of 20 six-star lists solved with
fov_deg given, 20 of 20 with nothing given). Only a failing search of such a short list pays for
it (a failing 30-star list of random points would take three times as long, 19 -> 54-63 ms CPU).

A mirror image has the same edge ratios but no rotation fits it, so step 4 rejects it; with
``mirrored=(False, True)`` the search also runs on the image's left-right flip, taking turns with
the image as given one look-up step at a time (:mod:`._parity`).
"""

from __future__ import annotations

import functools
import math
import time
import weakref
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ..camera import Camera
from ..errors import InvalidInputError
from ..results import Status
from ._candidate import Candidate, MatchOutcome
from ._confirm import Confirmer, StarSet, match_radius_px
from ._database import PatternDatabase
from ._options_base import MatcherOptionsBase
from ._parity import unmirrored
from ._quad_search import Fits, SearchSetup, focal_grid, search_batch, warm_up
from ._refine import pixel_vectors
from ._verify import SkyBands

MAX_RATIO_TOLERANCE = 0.1
"""Patterns whose edge ratios are less certain than this (tiny patterns) are not looked up."""


@dataclass(frozen=True)
class MatcherOptions(MatcherOptionsBase):
    """Settings of the lost-in-space matcher.

    Attributes
    ----------
    pattern_stars : int
        Image stars combined into patterns at a time (C(20, 4) = 4845 patterns at most, tried
        brightest first until one verifies or time runs out).
    verify_stars : int
        Brightest image stars tested against the predicted catalog stars.
    centroid_sigma_px : float
        Assumed 1-sigma centroid error; sets the pattern tolerances (3 sigma).
    match_radius_px : float or None
        Verification radius; None: 0.3 % of the larger image side, at least 2 px. A candidate
        that falls short at it is fitted to its matches at a wider radius and verified again
        (:mod:`._confirm`).
    max_false_match_prob : float
        A match is accepted only when its false-match bound is below this.
    focal_step : float
        Largest change of an edge ratio between two trial focal lengths.
    timeout_s : float
        Give up (status TIMEOUT) after this much wall-clock time.
    max_distortion : float
        Bound on |k1| of a lens that is not calibrated (the radial distortion
        r -> r (1 + k1 r^2) of the normalised pinhole radius r = tan(angle off axis)): the
        pattern tolerances allow for it (:func:`.quad_kernel.shape_bound`), and a candidate's
        confirmation fits k1. Ignored with a calibrated camera.
    max_pattern_stars : int
        When no pattern of the first ``pattern_stars`` stars matches, the pool slides on by half
        its size (stars 10-29, then 20-39, ...) up to this many stars: bright spots that are not
        stars (nebula knots, glow, a lit foreground) can fill the first pool.
    """

    pattern_stars: int = 20
    centroid_sigma_px: float = 0.5
    focal_step: float = 0.0015
    timeout_s: float = 5.0
    max_distortion: float = 0.05
    max_pattern_stars: int = 60

    def __post_init__(self) -> None:
        _check_options(self)


@functools.cache
def _default_options() -> MatcherOptions:
    """The default :class:`MatcherOptions`, checked once (they are immutable)."""
    return MatcherOptions()


def _check_options(options: MatcherOptions) -> None:
    """Refuse settings the search cannot use, naming the field."""
    for name in ("pattern_stars", "verify_stars", "max_pattern_stars"):
        value = getattr(options, name)
        if not (isinstance(value, int | np.integer) and value >= 4):
            raise InvalidInputError(f"MatcherOptions.{name} must be a whole number of stars >= 4, got {value!r}")
    for name in ("centroid_sigma_px", "max_false_match_prob", "focal_step", "timeout_s"):
        value = getattr(options, name)
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise InvalidInputError(f"MatcherOptions.{name} must be a positive finite number, got {value!r}")
    if not (isinstance(options.max_distortion, int | float) and 0 <= options.max_distortion <= 1):
        raise InvalidInputError(f"MatcherOptions.max_distortion must be between 0 and 1, "
                                f"got {options.max_distortion!r}")
    radius = options.match_radius_px
    if radius is not None and not (isinstance(radius, int | float) and math.isfinite(radius) and radius > 0):
        raise InvalidInputError(f"MatcherOptions.match_radius_px must be None or a positive number of pixels, "
                                f"got {radius!r}")


FIRST_BATCH_STARS = 6
"""The first batch holds every pattern of the 6 brightest stars (15 patterns)."""


def pattern_batches(n: int, first_new: int = 0) -> tuple[NDArray[np.int64], ...]:
    """Four-star combinations of ``n`` stars (brightest first), in batches: the first holds every
    pattern of the brightest :data:`FIRST_BATCH_STARS`, each later one every pattern whose
    faintest star is the next star; inside a batch, patterns of brighter stars come first.
    With ``first_new`` > 0 only the patterns with a star at index ``first_new`` or beyond (those
    a pool of the first ``first_new`` stars did not hold), one batch per faintest star.
    (Cached, read-only.)"""
    return _pattern_batches(int(n), int(first_new))


@functools.cache
def _pattern_batches(n: int, first_new: int) -> tuple[NDArray[np.int64], ...]:
    first = min(n, FIRST_BATCH_STARS) if first_new == 0 else first_new
    batches = [_read_only(_combinations(first, 4))] if first_new == 0 and first >= 4 else []
    batches.extend(_ending_at(last) for last in range(max(first, 3), n))
    return tuple(batches)


@functools.cache
def _ending_at(last: int) -> NDArray[np.int64]:
    """Every four-star pattern whose faintest star is ``last``: the triples of brighter stars in
    lexicographic order, then ``last``, shape (C(last, 3), 4) (cached, read-only; shared by the
    batches of every star count, so a solve with a new count builds none of them)."""
    head = _combinations(last, 3)
    return _read_only(np.column_stack([head, np.full(len(head), last, dtype=np.int64)]))


def _combinations(m: int, r: int) -> NDArray[np.int64]:
    """``itertools.combinations(range(m), r)`` as an array (C(m, r), r), in the same
    (lexicographic) order: the strictly increasing index tuples of an r-dimensional grid, which
    ``np.indices`` lists in that order, without a Python loop per combination."""
    grid = np.indices((m,) * r).reshape(r, -1)
    return np.ascontiguousarray(grid[:, np.all(grid[:-1] < grid[1:], axis=0)].T, dtype=np.int64)


def _read_only(array: NDArray) -> NDArray:
    """``array`` itself, made read-only (a cached batch is shared by every solve)."""
    array.flags.writeable = False
    return array


def pattern_pools(n: int, size: int, limit: int) -> list[tuple[int, int]]:
    """The pools of image stars the search forms patterns from, as (start, first_new) star ranks
    of ``n`` distinct stars: the first ``size`` stars, then windows of ``size`` stars sliding on
    by half a pool while their end stays within ``limit`` (and ``n``). ``first_new`` is the
    first rank the previous pool did not hold, relative to ``start``."""
    pools, end = [(0, 0)], min(n, size)
    step = max(1, size // 2)
    while end < min(n, limit):
        start = end + step - size
        pools.append((start, end - start))
        end = min(start + size, n, limit)
    return pools


MIN_SEPARATION_PX = 1.0
"""A star closer than this to a brighter one takes no part in patterns (coincident entries)."""


def distinct_stars(x: NDArray, y: NDArray, count: int) -> NDArray[np.int64]:
    """The first ``count`` stars (in order) that are not within MIN_SEPARATION_PX of a brighter one."""
    n = min(len(x), 4 * count)  # enough candidates, and the (n, n) test stays small
    d2 = (x[:n, None] - x[None, :n]) ** 2 + (y[:n, None] - y[None, :n]) ** 2
    close = (d2 < MIN_SEPARATION_PX**2) & _below_diagonal(n)  # pairs (i, j) with j brighter than i
    return np.flatnonzero(~close.any(axis=1))[:count]


@functools.cache
def _below_diagonal(n: int) -> NDArray[np.bool_]:
    """The (n, n) mask of the entries below the diagonal (j < i), made once per size (read-only)."""
    mask = np.tri(n, n, k=-1, dtype=bool)
    mask.flags.writeable = False
    return mask


class _Search:
    """State of one lost-in-space search with one nominal camera (one pixel aspect).

    ``trials`` is shared between the searches of one solve (a list holding the count of
    candidates tried so far): the false-match bound multiplies by all of them."""

    def __init__(self, x, y, camera: Camera, focal_range, db: PatternDatabase, options: MatcherOptions,
                 trials: list[int], shape_floor: float = 0.0, fit_aspect: bool = False, level_slack: float = 1.0):
        self.x, self.y, self.camera, self.db, self.options, self.trials = x, y, camera, db, options, trials
        vec = pixel_vectors(camera, x, y)
        self.u, self.w = vec[:, 0] / vec[:, 2], vec[:, 1] / vec[:, 2]
        calibrated = focal_range is None
        focal_range = focal_range or (camera.fx, camera.fx)
        fit_focal = focal_range[1] > focal_range[0]
        grid = focal_grid((camera.fx / focal_range[1], camera.fx / focal_range[0]), options.focal_step)
        tall = camera.fx / camera.fy  # a y pixel spans this many x pixels' angle
        distortion = 0.0 if calibrated else options.max_distortion
        short, long = sorted((camera.width, camera.height * tall))
        self.setup = SearchSetup(grid, camera.fx, short, math.sqrt(short * long),
                                 options.centroid_sigma_px * max(1.0, tall), options.focal_step, MAX_RATIO_TOLERANCE,
                                 fit_focal, distortion, shape_floor, level_slack)
        self.confirmer = Confirmer(x, y, match_radius_px(camera, options.match_radius_px), options.verify_stars,
                                   options.max_false_match_prob, fit_focal,
                                   fit_distortion=distortion > 0 and camera.fov_long_deg >= CONFIRM_K1_FOV_DEG,
                                   fit_aspect=fit_aspect)
        self.pattern_index = distinct_stars(x, y, options.max_pattern_stars)

    def batch_steps(self, quads: NDArray, start: int, deadline: float) -> Iterator[Candidate | None]:
        """Look up and verify a batch of patterns (indices into :attr:`pattern_index`, offset by
        ``start``), one step at a time: the look-up stops at each pattern that yields candidates,
        and the step yields the first of them that verifies, or None (also when ``deadline``, a
        ``time.perf_counter`` value, passes while they are confirmed: a pattern of a dense
        field can yield thousands)."""
        patterns, next_pattern = self.pattern_index[quads + start], 0
        while next_pattern < len(patterns):
            fits = search_batch(self.db, self.u, self.w, patterns, self.setup, next_pattern)
            self.trials[0] += fits.n_tried
            next_pattern = fits.next_pattern
            yield self._confirmed(fits, patterns, deadline) if fits.row.size else None

    def _confirmed(self, fits: Fits, patterns: NDArray[np.int64], deadline: float) -> Candidate | None:
        pool_end = int(patterns.max()) + 1
        levels = np.searchsorted(self.db.level_offsets, fits.row, side="right") - 1
        for i in range(fits.row.size):
            found = self.confirmer.confirm(self._level_stars(int(levels[i])), fits.quat[i],
                                           self.camera.with_focal(fits.focal[i]), fits.image_stars[i],
                                           self.trials[0], pool_end)
            if found is not None or time.perf_counter() > deadline:
                return found
        return None

    def _level_stars(self, level: int) -> StarSet:
        return level_stars(self.db, level)

    def reachable_levels(self) -> NDArray[np.int64]:
        """The database levels a look-up of this search can return candidates from: those whose
        field of view lies within the level ratio of the fields of view of the focal grid, from
        the short side's at the grid's smallest scale to the area's square's at its largest (the
        test of :func:`.quad_kernel._level_fits`, over the whole grid)."""
        s, scales = self.setup, self.setup.grid
        fov_lo, fov_hi = (2.0 * math.atan(side * scale / (2.0 * s.focal_nominal))
                          for side, scale in ((s.short_px, float(scales.min())), (s.square_px, float(scales.max()))))
        ratio = self.db.settings.level_ratio * s.level_slack
        return np.flatnonzero((self.db.level_fov_rad >= fov_lo / ratio) & (self.db.level_fov_rad <= fov_hi * ratio))


class _DatabaseStars:
    """The verification star sets of one database, by level, and the order of all its stars by
    ICRS z (one sort; each level's stars are read in that order, so their :class:`.verify.SkyBands`
    index needs no sort of its own)."""

    def __init__(self, db: PatternDatabase):
        self.z_order = np.argsort(db.vectors[:, 2])
        self.levels: dict[int, StarSet] = {}


_LEVEL_STARS: dict[int, _DatabaseStars] = {}
"""Each loaded database's :class:`_DatabaseStars` (keyed by ``id(db)``; an entry goes with its database)."""


def level_stars(db: PatternDatabase, level: int) -> StarSet:
    """Level ``level``'s verification stars of ``db`` (those whose bit k of
    :attr:`PatternDatabase.verify_levels` is set) as a :class:`.confirm.StarSet` over a
    :class:`.verify.SkyBands` index, in ascending order of z: made on first use, then kept while
    the database lives. The first call for a database sorts its stars by z (once); a level is
    then a selection in that order, much cheaper than building a KD-tree
    (:meth:`PatternDatabase.verification_stars`) for each level first used inside a solve, and a
    cone query reads one band of z."""
    stars = _LEVEL_STARS.get(id(db))
    if stars is None:
        stars = _LEVEL_STARS[id(db)] = _DatabaseStars(db)
        weakref.finalize(db, _LEVEL_STARS.pop, id(db), None)
    if level not in stars.levels:
        bits = db.verify_levels.dtype.type
        members = stars.z_order[((db.verify_levels[stars.z_order] >> bits(level)) & bits(1)).astype(bool)]
        vectors = np.take(db.vectors, members, axis=0)  # faster than db.vectors[members] here
        stars.levels[level] = StarSet(SkyBands(vectors), vectors, db.cat_index[members])
    return stars.levels[level]


_INDEXED: set[tuple] = set()
"""(id of the database, id of the focal grid, short side, area's square side, nominal focal length,
level slack) of the searches whose levels :func:`_index_levels` has indexed (the grids are cached
by :func:`.quad_search.focal_grid`)."""


def _index_levels(db: PatternDatabase, searches: list[_Search]) -> None:
    """Index (:func:`level_stars`) the verification stars of every level the searches can reach,
    once per database and search geometry, so that no level is first indexed inside a solve's
    timed search; a check here costs a set look-up."""
    for search in searches:
        setup = search.setup
        key = (id(db), id(setup.grid), setup.short_px, setup.square_px, setup.focal_nominal, setup.level_slack)
        if key not in _INDEXED:
            for level in search.reachable_levels().tolist():
                level_stars(db, level)
            _INDEXED.add(key)


CONFIRM_K1_FOV_DEG = 25.0
"""The confirmation of a candidate from a lens that is not calibrated fits k1 when the nominal
field is at least this wide along the image's long side (narrower, k1 is poorly determined by a
few stars and moves them by less than the match radius)."""

ASPECT_TOLERANCE = 0.005
"""A searched pixel aspect is tried in steps of twice this (relative), each trial's patterns
allowing an edge stretch of this much (:func:`aspect_trials`)."""


def aspect_trials(aspect_range: tuple[float, float]) -> NDArray[np.float64]:
    """Pixel aspects (fx / fy) to try for a range (lo, hi): geometric steps of 2 ASPECT_TOLERANCE,
    nearest to 1 (square pixels) first, so a search stops soonest for the commonest sensors."""
    lo, hi = aspect_range
    count = max(1, math.ceil(math.log(hi / lo) / math.log1p(2 * ASPECT_TOLERANCE)))
    edges = np.geomspace(lo, hi, count + 1)
    centres = np.sqrt(edges[:-1] * edges[1:])
    return centres[np.argsort(np.abs(np.log(centres)), kind="stable")]


def _searches(x: NDArray, y: NDArray, camera: Camera, focal_range_px, db: PatternDatabase, options: MatcherOptions,
              trials: list[int], aspect_range: tuple[float, float] | None, fit_aspect: bool,
              mirrored: tuple[bool, ...], level_slack: float = 1.0) -> list[tuple[_Search, bool]]:
    """The searches of a solve with their hypothesis (True: a mirror image, searched through the
    plain camera on the flipped columns, :func:`._parity.unmirrored`): for each of ``mirrored``,
    one, or one per pixel aspect of ``aspect_range``; their window of levels widened by
    ``level_slack`` (:class:`.quad_search.SearchSetup`)."""
    out = []
    for flip in mirrored:
        seen_camera, seen_x = unmirrored(replace(camera, mirrored=True), x) if flip else (camera, x)
        if aspect_range is None:
            out.append((_Search(seen_x, y, seen_camera, focal_range_px, db, options, trials, fit_aspect=fit_aspect,
                                level_slack=level_slack), flip))
            continue
        out += [(_Search(seen_x, y, seen_camera.with_focal(seen_camera.fx, seen_camera.fx / a), focal_range_px, db,
                         options, trials, ASPECT_TOLERANCE, True, level_slack), flip)
                for a in aspect_trials(aspect_range)]
    return out


def _wider(searches: list[tuple[_Search, bool]], make: Callable[[float], list[tuple[_Search, bool]]],
           ratio: float) -> list[tuple[_Search, bool]] | None:
    """The searches again with their window of levels one level wider each way
    (``make(level_slack)``), or None when that reaches no level they did not search."""
    wider = make(ratio)
    more = any(np.setdiff1d(w.reachable_levels(), s.reachable_levels()).size
               for (w, _), (s, _) in zip(wider, searches, strict=True))
    return wider if more else None


def _taking_turns(searches: list[tuple[_Search, bool]], quads: NDArray, start: int,
                  deadline: float) -> Iterator[tuple[Candidate | None, bool]]:
    """The steps (:meth:`_Search.batch_steps`) of every search on one batch, one step of each in
    turn until all are done, each with its search's flag (True: the mirror image): an aspect or
    a parity that does not fit a frame and makes many candidates cannot hold the others back
    for long. (Before the mirror images, the searches of several aspects took turns batch by
    batch.)"""
    turns = [(search.batch_steps(quads, start, deadline), flip) for search, flip in searches]
    while turns:
        for turn in list(turns):
            try:
                step = next(turn[0])
            except StopIteration:
                turns.remove(turn)
                continue
            yield step, turn[1]


def _search_patterns(searches: list[tuple[_Search, bool]], n_stars: int, options: MatcherOptions, trials: list[int],
                     deadline: float) -> MatchOutcome | None:
    """Search the pattern pools and batches of the image's ``n_stars`` distinct stars, the
    searches taking turns: the first candidate that verifies (OK), TIMEOUT past ``deadline``, or
    None when every pattern was looked up without one."""
    for start, first_new in pattern_pools(n_stars, options.pattern_stars, options.max_pattern_stars):
        for quads in pattern_batches(min(options.pattern_stars, n_stars - start), first_new):
            for found, flip in _taking_turns(searches, quads, start, deadline):
                if found is not None:
                    if flip:  # found in the flipped columns: the camera of the image as given is mirrored
                        found = replace(found, camera=found.camera.mirror_image())
                    return MatchOutcome(Status.OK, "", found, trials[0])
                if time.perf_counter() > deadline:
                    return MatchOutcome(Status.TIMEOUT, f"no match within the {options.timeout_s:g} s time limit",
                                        None, trials[0])
    return None


def match_lost_in_space(x: NDArray, y: NDArray, camera: Camera, db: PatternDatabase,
                        focal_range_px: tuple[float, float] | None = None,
                        options: MatcherOptions | None = None,
                        aspect_range: tuple[float, float] | None = None, fit_aspect: bool = False,
                        mirrored: tuple[bool, ...] = (False,)) -> MatchOutcome:
    """Identify image stars with no prior attitude.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Star positions (our pixel convention), brightest (or most trusted) first.
    camera : Camera
        Image size, principal point and distortion; its focal lengths are the nominal ones.
    db : PatternDatabase
    focal_range_px : (float, float) or None
        Range of focal lengths fx to search (pixels); None: the camera is calibrated (focal
        length and distortion known).
    options : MatcherOptions or None
    aspect_range : (float, float) or None
        Range of pixel aspects fx / fy to search (:func:`aspect_trials`); None: the camera's.
    fit_aspect : bool
        The camera's pixel aspect is a guess: the confirmation refits it (always when a range
        is searched).
    mirrored : tuple of bool
        The hypotheses to search, taking turns step by step: False the image as given, True a
        mirror image of the sky (:mod:`._parity`; the candidate's camera is then ``mirrored``).

    Returns
    -------
    MatchOutcome
        With a :class:`Candidate` when the false-match bound is below the threshold; otherwise
        status NO_MATCH, TOO_FEW_STARS or TIMEOUT and a reason.
    """
    options = options or _default_options()
    if len(x) < 4:
        return MatchOutcome(Status.TOO_FEW_STARS,
                            f"lost-in-space identification needs at least 4 stars, got {len(x)}", None, 0)
    x, y, trials = np.asarray(x, float), np.asarray(y, float), [0]

    def make(level_slack: float) -> list[tuple[_Search, bool]]:
        return _searches(x, y, camera, focal_range_px, db, options, trials, aspect_range, fit_aspect, mirrored,
                         level_slack)

    searches = make(1.0)
    warm_up(db)  # compiling is not searching: before the clock starts
    _index_levels(db, [search for search, _ in searches])  # nor is indexing the levels' verification stars
    deadline = time.perf_counter() + options.timeout_s
    n_stars = searches[0][0].pattern_index.size
    outcome = _search_patterns(searches, n_stars, options, trials, deadline)
    if outcome is None and n_stars < options.pattern_stars:  # a sparse list: its patterns can lie in the
        wider = _wider(searches, make, db.settings.level_ratio)  # levels next to the field's (module docstring)
        if wider is not None:
            _index_levels(db, [search for search, _ in wider])
            outcome = _search_patterns(wider, n_stars, options, trials, deadline)
    if outcome is not None:
        return outcome
    return MatchOutcome(Status.NO_MATCH, f"no pattern of the {min(n_stars, options.max_pattern_stars)} brightest "
                        f"distinct stars matched the catalog with a false-match probability below "
                        f"{options.max_false_match_prob:g} ({trials[0]} candidates tried)", None, trials[0])
