"""Lost-in-space identification by four-star patterns, with an unknown or known focal length.

The default matcher. Steps (after tetra3's pattern hashing, with a sorted key index over all scales):

1. Form four-star patterns from the brightest image stars, brightest combinations first, in
   batches (:func:`pattern_batches`); steps 2-4 run on a whole batch at once
   (:mod:`.quad_search`).
2. For each, the image vectors depend on the focal length; when it is only known as a range,
   choose the few trial focal lengths that change the pattern's edge ratios by more than the
   tolerance. Wide fields need several, narrow fields one.
3. Look the ratios up in the levels of the database whose scale fits the trial field of view:
   key ranges on a key of the three smallest ratios, then all five ratios, then the scale.
4. For each candidate, take the star correspondence whose edges agree best, correct the focal
   length from the edge sums, fit the rotation (q-method) and check the residuals.
5. Verify against the level's verification stars and bound the false-match probability
   (:mod:`.confirm`, :mod:`.verify`); the first candidate below the threshold wins.
6. (In :mod:`startrack.solve`) refine attitude and focal length on all matched stars (:mod:`.refine`).

A mirror image has the same edge ratios but no rotation fits it, so step 4 rejects it.
"""

from __future__ import annotations

import functools
import itertools
import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..results import Status
from .candidate import Candidate, MatchOutcome
from .confirm import Confirmer, StarSet, match_radius_px
from .database import PatternDatabase
from .quad_search import Fits, SearchSetup, focal_grid, search_batch, warm_up

MAX_RATIO_TOLERANCE = 0.1
"""Patterns whose edge ratios are less certain than this (tiny patterns) are not looked up."""


@dataclass(frozen=True)
class MatcherOptions:
    """Settings of the lost-in-space matcher.

    Attributes
    ----------
    pattern_stars : int
        Brightest image stars combined into patterns (C(20, 4) = 4845 patterns at most, tried
        brightest first until one verifies or time runs out).
    verify_stars : int
        Brightest image stars tested against the predicted catalog stars.
    centroid_sigma_px : float
        Assumed 1-sigma centroid error; sets the pattern tolerances (3 sigma).
    match_radius_px : float or None
        Verification radius; None: 0.3 % of the larger image side, at least 2 px. A candidate
        that falls short at it is fitted to its matches at a wider radius and verified again
        (:mod:`.confirm`).
    max_false_match_prob : float
        A match is accepted only when its false-match bound is below this.
    focal_step : float
        Largest change of an edge ratio between two trial focal lengths.
    timeout_s : float
        Give up (status TIMEOUT) after this much wall-clock time.
    """

    pattern_stars: int = 20
    verify_stars: int = 40
    centroid_sigma_px: float = 0.5
    match_radius_px: float | None = None
    max_false_match_prob: float = 1e-6
    focal_step: float = 0.0015
    timeout_s: float = 5.0


FIRST_BATCH_STARS = 6
"""The first batch holds every pattern of the 6 brightest stars (15 patterns)."""


def pattern_batches(n: int) -> tuple[NDArray[np.int64], ...]:
    """Four-star combinations of ``n`` stars (brightest first), in batches: the first holds every
    pattern of the brightest :data:`FIRST_BATCH_STARS`, each later one every pattern whose
    faintest star is the next star; inside a batch, patterns of brighter stars come first.
    (Cached per ``n``, read-only.)"""
    return _pattern_batches(int(n))


@functools.cache
def _pattern_batches(n: int) -> tuple[NDArray[np.int64], ...]:
    first = min(n, FIRST_BATCH_STARS)
    batches = [np.array(list(itertools.combinations(range(first), 4)), dtype=np.int64)] if first >= 4 else []
    for last in range(first, n):
        head = np.array(list(itertools.combinations(range(last), 3)), dtype=np.int64)
        batches.append(np.column_stack([head, np.full(len(head), last)]))
    for batch in batches:
        batch.flags.writeable = False
    return tuple(batches)


MIN_SEPARATION_PX = 1.0
"""A star closer than this to a brighter one takes no part in patterns (coincident entries)."""


def distinct_stars(x: NDArray, y: NDArray, count: int) -> NDArray[np.int64]:
    """The first ``count`` stars (in order) that are not within MIN_SEPARATION_PX of a brighter one."""
    n = min(len(x), 4 * count)  # enough candidates, and the (n, n) test stays small
    d2 = (x[:n, None] - x[None, :n]) ** 2 + (y[:n, None] - y[None, :n]) ** 2
    close = np.tril(d2 < MIN_SEPARATION_PX**2, k=-1)  # pairs (i, j) with j brighter than i
    return np.flatnonzero(~close.any(axis=1))[:count]


class _Search:
    """State of one lost-in-space search."""

    def __init__(self, x, y, camera: Camera, focal_range, db: PatternDatabase, options: MatcherOptions):
        self.x, self.y, self.camera, self.db, self.options = x, y, camera, db, options
        vec = camera.pixel_to_vector(x, y)
        self.u, self.w = vec[:, 0] / vec[:, 2], vec[:, 1] / vec[:, 2]
        fit_focal = focal_range[1] > focal_range[0]
        grid = focal_grid((camera.fx / focal_range[1], camera.fx / focal_range[0]), options.focal_step)
        self.setup = SearchSetup(grid, camera.fx, min(camera.width, camera.height), options.centroid_sigma_px,
                                 options.focal_step, MAX_RATIO_TOLERANCE, fit_focal)
        self.confirmer = Confirmer(x, y, match_radius_px(camera, options.match_radius_px), options.verify_stars,
                                   options.max_false_match_prob, fit_focal)
        self.trials = 0
        self.pattern_index = distinct_stars(x, y, options.pattern_stars)

    def try_batch(self, quads: NDArray) -> Candidate | None:
        """Look up and verify a batch of patterns (indices into :attr:`pattern_index`); the first
        verified candidate wins. The look-up stops at each pattern that yields candidates, to
        confirm them before searching the rest."""
        patterns, next_pattern = self.pattern_index[quads], 0
        while next_pattern < len(patterns):
            fits = search_batch(self.db, self.u, self.w, patterns, self.setup, next_pattern)
            self.trials += fits.n_tried
            next_pattern = fits.next_pattern
            found = self._confirmed(fits)
            if found is not None:
                return found
        return None

    def _confirmed(self, fits: Fits) -> Candidate | None:
        levels = np.searchsorted(self.db.level_offsets, fits.row, side="right") - 1
        for i in range(fits.row.size):
            found = self.confirmer.confirm(self._level_stars(int(levels[i])), Rotation.from_quat(fits.quat[i]),
                                           self.camera.with_focal(fits.focal[i]), fits.image_stars[i], self.trials)
            if found is not None:
                return found
        return None

    def _level_stars(self, level: int) -> StarSet:
        return StarSet(*self.db.verification_stars(level))


def match_lost_in_space(x: NDArray, y: NDArray, camera: Camera, db: PatternDatabase,
                        focal_range_px: tuple[float, float] | None = None,
                        options: MatcherOptions | None = None) -> MatchOutcome:
    """Identify image stars with no prior attitude.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Star positions (our pixel convention), brightest first.
    camera : Camera
        Image size, principal point and distortion; its focal length is the nominal one.
    db : PatternDatabase
    focal_range_px : (float, float) or None
        Range of focal lengths to search (pixels); None: the camera's focal length is known.
    options : MatcherOptions or None

    Returns
    -------
    MatchOutcome
        With a :class:`Candidate` when the false-match bound is below the threshold; otherwise
        status NO_MATCH, TOO_FEW_STARS or TIMEOUT and a reason.
    """
    options = options or MatcherOptions()
    if len(x) < 4:
        return MatchOutcome(Status.TOO_FEW_STARS,
                            f"lost-in-space identification needs at least 4 stars, got {len(x)}", None, 0)
    focal_range = focal_range_px or (camera.fx, camera.fx)
    search = _Search(np.asarray(x, float), np.asarray(y, float), camera, focal_range, db, options)
    warm_up(db)  # compiling is not searching: before the clock starts
    deadline = time.perf_counter() + options.timeout_s
    for quads in pattern_batches(search.pattern_index.size):
        found = search.try_batch(quads)
        if found is not None:
            return MatchOutcome(Status.OK, "", found, search.trials)
        if time.perf_counter() > deadline:
            return MatchOutcome(Status.TIMEOUT, f"no match within the {options.timeout_s:g} s time limit",
                                None, search.trials)
    return MatchOutcome(Status.NO_MATCH, f"no pattern of the {min(len(x), options.pattern_stars)} brightest "
                        f"stars matched the catalog with a false-match probability below "
                        f"{options.max_false_match_prob:g} ({search.trials} candidates tried)", None, search.trials)
