"""Look-up of a batch of four-star image patterns in the pattern database, compiled.

The steps of :mod:`._quad_matcher` for a whole batch of image patterns, in one compiled loop
(numba): a lost-in-space solve is a few thousand tiny operations, and as numpy calls their
overhead, not the arithmetic, set its time. For each pattern, in order:

1. Trial focal lengths (scales f_nominal / f): on :func:`focal_grid`, a new trial starts where
   the pattern's edge ratios have moved by more than the focal step since the last one, so a
   pattern near the centre of a narrow field needs one, a wide pattern of a wide field several.
   The ratios are evaluated at every eighth grid point and their change spread evenly between
   (they are smooth in the scale; evaluating all 131 points of a 5-35 deg range took nearly half
   of a batch's time at FOV 20).
   A known focal length is one trial.
2. At each trial: the six edge angles, the five ratios (sorted, over the largest) and their
   tolerances: the focal step plus a 3-sigma centroid error propagated into the ratio of two
   edges measured in pixels.
3. The database levels whose scale suits the trial's range of fields of view; in each, one key
   range per pair of bins of the two smallest ratios (the key of
   :func:`startrack.identify._database.pattern_key`, binary search on
   :attr:`PatternDatabase.keys`); then all five ratios, and the focal length the largest edge
   implies, must fit.
4. For each candidate row: the star correspondence of the 24 orderings whose edges agree best,
   the focal length corrected from the edge sums (when it is free), the rotation of the four
   stars (Wahba's problem by Davenport's q-method) and the residual test.

Candidates come out in the order the patterns were formed (brightest stars first), then by
trial, level and key. A call stops after the first pattern that yields candidates, so that they
are confirmed before the rest of the batch is searched (searching all 15 patterns of the first
batch before confirming made FOV-range solves measurably slower; ``benchmarks/lis_benchmark.py``
times the solves).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ._database import PatternDatabase

FOCAL_GRID = 48
FOCAL_GRID_SPAN = 7.0
FOCAL_GRID_STEP = 0.004
"""The trials are chosen on a logarithmic grid of focal lengths with FOCAL_GRID points per
factor FOCAL_GRID_SPAN for a ratio step of FOCAL_GRID_STEP, proportionally more for a finer
step (48 points from 5 to 35 deg at 0.004; 3 for a FOV known to a few percent)."""

@functools.lru_cache(maxsize=64)
def focal_grid(scale_range: tuple[float, float], step: float) -> NDArray[np.float64]:
    """Scales (f_nominal / f) the trials of every pattern are chosen from.

    Parameters
    ----------
    scale_range : (float, float)
        Smallest and largest f_nominal / f.
    step : float
        Largest edge-ratio change a trial may stand for.

    Returns
    -------
    ndarray, shape (G,)
        Ascending, read-only (grids are cached: a camera asks for the same one every solve); a
        single scale when the range is a point (a known focal length).
    """
    lo, hi = scale_range
    if hi <= lo * (1 + 1e-9):
        grid = np.array([lo])
    else:
        density = FOCAL_GRID * max(1.0, FOCAL_GRID_STEP / step)  # finer steps need a finer grid
        grid = np.geomspace(lo, hi, max(3, math.ceil(density * math.log(hi / lo) / math.log(FOCAL_GRID_SPAN))))
    grid.flags.writeable = False
    return grid


@dataclass(frozen=True)
class SearchSetup:
    """What stays fixed over one search: the trial grid and the tolerances.

    Attributes
    ----------
    grid : ndarray, shape (G,)
        From :func:`focal_grid`.
    focal_nominal : float
        The nominal focal length (pixels); a scale s stands for focal length focal_nominal / s.
    short_px : float
        Shorter image side in units of x pixels (the height times fx / fy when it is the
        shorter): sets the smallest field of view a level may suit.
    square_px : float
        Side of the square of the image's area, sqrt(short x long side), in units of x pixels:
        sets the largest field of view a level may suit (the level's star density suits a
        square field of that area; a wide image's patterns fit levels its short side does not
        reach). Equal to ``short_px`` for a square image.
    sigma_px : float
        Assumed 1-sigma centroid error (pixels).
    focal_step : float
        Largest edge-ratio change between trials.
    max_tolerance : float
        Patterns with a ratio less certain than this are not looked up.
    fit_focal : bool
        Correct the focal length of each candidate from its edge sums.
    distortion : float
        Bound on |k1| of the lens (normalised pinhole radius r -> r (1 + k1 r^2)) that the
        tolerances allow for; 0 for a calibrated camera.
    shape_floor : float
        Relative stretch of one edge against another allowed in every pattern (a pixel aspect
        searched in steps of twice this).
    level_slack : float
        The window of levels searched around the fields of view of the grid is the database's
        level ratio times this, each way (1: as the database is built; the level ratio: one
        level further, the second pass of :func:`.quad_matcher.match_lost_in_space`).
    """

    grid: NDArray[np.float64]
    focal_nominal: float
    short_px: float
    square_px: float
    sigma_px: float
    focal_step: float
    max_tolerance: float
    fit_focal: bool
    distortion: float = 0.0
    shape_floor: float = 0.0
    level_slack: float = 1.0


class Fits(NamedTuple):
    """Candidates whose four stars fit a rotation, in search order (a named tuple: made once
    per look-up call, of which a solve makes up to a few dozen).

    Attributes
    ----------
    quat : ndarray, shape (C, 4)
        Attitudes, camera from ICRS, as scalar-last quaternions (scipy's order).
    focal : ndarray, shape (C,)
        Focal length (pixels).
    image_stars : ndarray of int, shape (C, 4)
        The image star matching each of the database pattern's four stars.
    row : ndarray of int, shape (C,)
        Database pattern row.
    n_tried : int
        Candidates whose edges matched (the count the false-match bound multiplies by).
    next_pattern : int
        The pattern after the last one searched: the batch's size when every pattern was searched.
    """

    quat: NDArray[np.float64]
    focal: NDArray[np.float64]
    image_stars: NDArray[np.int64]
    row: NDArray[np.int64]
    n_tried: int
    next_pattern: int


def search_batch(db: PatternDatabase, u: NDArray, w: NDArray, quads: NDArray, setup: SearchSetup,
                 first: int = 0) -> Fits:
    """Look up the image patterns of a batch, from pattern ``first`` up to and including the first
    that yields candidates (see the module docstring): the caller confirms those before paying for
    the rest of the batch, and continues from :attr:`Fits.next_pattern` if none holds.

    Parameters
    ----------
    db : PatternDatabase
    u, w : ndarray, shape (N,)
        Normalised pinhole coordinates (x / z, y / z) of the image stars at the nominal focal length.
    quads : ndarray of int, shape (P, 4)
        Image-star indices of the patterns, in the order to try them.
    setup : SearchSetup
    first : int
        Index (into ``quads``) of the first pattern to search.

    Returns
    -------
    Fits
    """
    s = db.settings
    quat, focal, stars, row, n_tried, next_pattern = _kernel()(
        np.ascontiguousarray(u, dtype=np.float64), np.ascontiguousarray(w, dtype=np.float64),
        np.ascontiguousarray(quads, dtype=np.int64), setup.grid, float(setup.focal_nominal),
        float(setup.short_px), float(setup.square_px), float(setup.sigma_px), float(setup.focal_step),
        float(setup.max_tolerance), bool(setup.fit_focal), float(setup.distortion), float(setup.shape_floor),
        db.level_fov_rad, float(s.level_ratio * setup.level_slack), float(s.region_fraction), db.keys, db.cell_starts,
        db.pattern_ratios, db.pattern_largest, db.pattern_stars, db.vectors, int(first))
    return Fits(quat, focal, stars, row, int(n_tried), int(next_pattern))


@functools.cache
def _kernel():
    """The compiled search (:func:`.quad_kernel.search`): numba is imported on first use."""
    from ._quad_kernel import search

    return search


_WARM: set[tuple[np.dtype, ...]] = set()


def warm_up(db: PatternDatabase) -> None:
    """Compile (or load from the disk cache) the search for this database's array types, so
    that a solve's time and time limit do not include it. Free after the first call."""
    types = (db.keys.dtype, db.pattern_ratios.dtype, db.pattern_largest.dtype, db.pattern_stars.dtype)
    if types in _WARM:
        return
    u = np.array([0.0, 0.01, 0.0, 0.01])
    w = np.array([0.0, 0.0, 0.01, 0.012])
    setup = SearchSetup(focal_grid((1.0, 1.0), 0.0015), 1000.0, 1000, 1000, 0.5, 0.0015, 0.1, False)  # as in use
    search_batch(db, u, w, np.array([[0, 1, 2, 3]]), setup)
    _WARM.add(types)
