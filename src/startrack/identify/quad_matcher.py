"""Lost-in-space identification by four-star patterns, with an unknown or known focal length.

The default matcher. Steps (after tetra3's pattern hashing, with a k-vector index per scale):

1. Form four-star patterns from the brightest image stars, brightest combinations first.
2. For each, the image vectors depend on the focal length; when it is only known as a range,
   choose the few trial focal lengths that change the pattern's edge ratios by more than the
   tolerance (:func:`focal_trials`). Wide fields need several, narrow fields one.
3. Look the ratios up in the levels of the database whose scale fits the trial field of view
   (:func:`lookup`): k-vector range on the smallest ratio, then all five ratios, then the scale.
4. For each candidate, take the star correspondence whose edges agree best, correct the focal
   length from the edge sums, fit the rotation (q-method) and check the residuals.
5. Verify against the level's verification stars and bound the false-match probability
   (:mod:`.verify`); the first candidate below the threshold wins.
6. Refine attitude and focal length on all matched stars (:mod:`.refine`).

A mirror image has the same edge ratios but no rotation fits it, so step 4 rejects it.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..attitude import solve_wahba
from ..camera import Camera
from ..frames import angle_between
from ..results import Status
from .database import KEY_BINS, RATIO_SCALE, PatternDatabase
from .patterns import best_correspondence, edge_ratios, pair_angles
from .refine import refine_pointing
from .verify import false_match_probability, match_nearest, project_catalog

LOOSE_RADIUS_FACTOR = 2.5
"""First verification pass: match radius as a multiple of the final one."""

MIN_EXTRA_MATCHES = 2
"""A candidate needs at least this many stars beyond its pattern at the loose radius."""

MAX_RATIO_TOLERANCE = 0.1
"""Patterns whose edge ratios are less certain than this (tiny patterns) are not looked up."""


@dataclass(frozen=True)
class MatcherOptions:
    """Settings of the lost-in-space matcher.

    Attributes
    ----------
    pattern_stars : int
        Brightest image stars combined into patterns (C(10, 4) = 210 patterns at most).
    verify_stars : int
        Brightest image stars tested against the predicted catalog stars.
    centroid_sigma_px : float
        Assumed 1-sigma centroid error; sets the pattern tolerances (3 sigma).
    match_radius_px : float or None
        Verification radius after the candidate is refined on its first matches (which are
        sought at 4 times this radius); None: 0.3 % of the larger image side, at least 2 px.
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
    focal_step: float = 0.004
    timeout_s: float = 5.0


@dataclass(frozen=True)
class Candidate:
    """A verified identification: attitude, camera and the matched (image, database) stars."""

    rot_cam_from_icrs: Rotation
    camera: Camera
    image_index: NDArray[np.int64]
    db_index: NDArray[np.int64]
    false_match_prob: float


@dataclass(frozen=True)
class MatchOutcome:
    """What the matcher found: a candidate, or a status and reason."""

    status: Status
    reason: str
    candidate: Candidate | None
    n_trials: int


def pattern_order(n: int) -> Iterator[tuple[int, int, int, int]]:
    """Four-star combinations of ``n`` stars, those of brighter stars first."""
    for last in range(3, n):
        for first in itertools.combinations(range(last), 3):
            yield (*first, last)


def _vectors(u: NDArray, w: NDArray, scale: NDArray | float) -> NDArray:
    """Unit vectors of normalised coordinates (u, w) scaled by ``scale`` (= f_nominal / f)."""
    u = u * np.asarray(scale)[..., None]
    w = w * np.asarray(scale)[..., None]
    v = np.stack([u, w, np.ones_like(u)], axis=-1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def focal_trials(u: NDArray, w: NDArray, scale_range: tuple[float, float],
                 step: float) -> list[tuple[float, float, float]]:
    """Trial scales (f_nominal / f) for one pattern, spaced so its edge ratios move by < step.

    Parameters
    ----------
    u, w : ndarray, shape (4,)
        Normalised pinhole coordinates of the pattern's stars at the nominal focal length.
    scale_range : (float, float)
        Smallest and largest f_nominal / f; equal when the focal length is known.

    Returns
    -------
    list of (scale, low, high)
        Each trial scale and the interval of scales it stands for (its ratios are within
        ``step`` of every scale in the interval).
    """
    lo, hi = scale_range
    if hi <= lo * (1 + 1e-9):
        return [(lo, lo, hi)]
    grid = np.geomspace(lo, hi, 48)
    ratios, _ = edge_ratios(pair_angles(_vectors(u, w, grid)))
    starts = [0]
    for i in range(1, grid.size):
        if np.max(np.abs(ratios[i] - ratios[starts[-1]])) > step:
            starts.append(i)
    ends = [*starts[1:], grid.size - 1]
    return [(grid[a], grid[a], grid[b]) for a, b in zip(starts, ends, strict=True)]


def _tolerances(angles: NDArray, focal_px: float, options: MatcherOptions) -> NDArray:
    """Ratio tolerances (5,) from the centroid error and the focal-length step."""
    edges_px = np.sort(angles) * focal_px
    ratios = edges_px[:5] / edges_px[5]
    noise = 3.0 * options.centroid_sigma_px * math.sqrt(2.0)
    return options.focal_step + noise * (1.0 / edges_px[:5] + ratios / edges_px[5])


def lookup(db: PatternDatabase, angles: NDArray, levels: NDArray[np.int64],
           focal_px: float, focal_window: tuple[float, float], options: MatcherOptions) -> NDArray[np.int64]:
    """Database pattern rows whose ratios and scale fit an image pattern.

    Parameters
    ----------
    angles : ndarray, shape (6,)
        The image pattern's edge angles at the trial focal length ``focal_px``.
    levels : ndarray of int
        Database levels to search.
    focal_window : (float, float)
        Focal lengths (px) this trial stands for; a pattern must imply one of them.
    """
    ratios, largest = edge_ratios(angles)
    tol = _tolerances(angles, focal_px, options)
    bins = np.arange(math.floor(max(ratios[0] - tol[0], 0.0) * KEY_BINS),
                     math.floor(min(ratios[0] + tol[0], 1.0) * KEY_BINS) + 1)
    low, high = 2.0 * bins + ratios[1] - tol[1], 2.0 * bins + ratios[1] + tol[1]
    q_lo = np.round((ratios - tol) * RATIO_SCALE)
    q_hi = np.round((ratios + tol) * RATIO_SCALE)
    rows = []
    for level in levels:
        offset = db.level_offsets[level]
        starts, stops = db.kvectors[level].query_many(low, high)
        idx = np.concatenate([np.arange(a, b) for a, b in zip(starts, stops, strict=True)]) + offset
        if idx.size == 0:
            continue
        stored = db.pattern_ratios[idx]
        idx = idx[np.all((stored >= q_lo) & (stored <= q_hi), axis=1)]
        focal = focal_px * largest / db.pattern_largest[idx]
        rows.append(idx[(focal >= focal_window[0] * 0.98) & (focal <= focal_window[1] * 1.02)])
    return np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)


def _levels_for(db: PatternDatabase, fov_short: tuple[float, float], largest: float) -> NDArray[np.int64]:
    """Levels whose scale suits an image whose short side spans ``fov_short`` (low, high)
    radians, and which can hold a pattern whose largest edge is at least ``largest``."""
    ratio = db.settings.level_ratio
    fit = (db.level_fov_rad >= fov_short[0] / ratio) & (db.level_fov_rad <= fov_short[1] * ratio)
    fit &= 2.0 * db.settings.region_fraction * db.level_fov_rad >= 0.95 * largest
    return np.flatnonzero(fit)


class _Search:
    """State of one lost-in-space search (a small object so the steps stay short functions)."""

    def __init__(self, x, y, camera: Camera, focal_range, db: PatternDatabase, options: MatcherOptions):
        self.x, self.y, self.camera, self.db, self.options = x, y, camera, db, options
        self.focal_range = focal_range
        vec = camera.pixel_to_vector(x, y)
        self.u, self.w = vec[:, 0] / vec[:, 2], vec[:, 1] / vec[:, 2]
        self.scale_range = (camera.fx / focal_range[1], camera.fx / focal_range[0])
        self.radius = options.match_radius_px or max(2.0, 0.003 * max(camera.width, camera.height))
        self.fit_focal = focal_range[1] > focal_range[0]
        self.trials = 0
        self.short = min(camera.width, camera.height)

    def try_pattern(self, quad: tuple[int, ...]) -> Candidate | None:
        q = np.array(quad)
        for scale, s_lo, s_hi in focal_trials(self.u[q], self.w[q], self.scale_range, self.options.focal_step):
            focal = self.camera.fx / scale
            window = (self.camera.fx / s_hi, self.camera.fx / s_lo)
            angles = pair_angles(_vectors(self.u[q], self.w[q], scale))
            if _tolerances(angles, focal, self.options).max() > MAX_RATIO_TOLERANCE:
                continue
            fov_short = tuple(2.0 * math.atan(self.short / (2.0 * f)) for f in (window[1], window[0]))
            levels = _levels_for(self.db, fov_short, float(angles.max()) * s_lo / scale)
            rows = lookup(self.db, angles, levels, focal, window, self.options)
            if rows.size:
                found = self._check(q, angles, scale, rows)
                if found is not None:
                    return found
        return None

    def _check(self, q, angles, scale, rows) -> Candidate | None:
        """Fit every candidate at once; confirm those whose four stars fit a rotation."""
        cat_vec = self.db.vectors[self.db.pattern_stars[rows]]  # (C, 4, 3)
        cat_angles = pair_angles(cat_vec)
        perm, misfit = best_correspondence(angles, cat_angles)
        keep = misfit <= 3.0 * _tolerances(angles, self.camera.fx / scale, self.options).max()
        if not np.any(keep):
            return None
        rows, img, cat_vec = rows[keep], q[perm[keep]], cat_vec[keep]
        self.trials += int(rows.size)
        scales = scale * cat_angles[keep].sum(axis=1) / angles.sum()  # focal from the edge sums
        obs = _vectors(self.u[img], self.w[img], scales)
        rot = solve_wahba(obs, cat_vec, method="qmethod").rotation
        predicted = np.einsum("cij,ckj->cki", rot.as_matrix(), cat_vec)
        focal = self.camera.fx / scales
        tol = 6.0 * self.options.centroid_sigma_px / focal + self.options.focal_step * angles.max()
        fits = np.flatnonzero(np.max(angle_between(predicted, obs), axis=1) <= tol)
        for i in fits:
            level = int(np.searchsorted(self.db.level_offsets, rows[i], side="right") - 1)
            found = self._confirm(rot[int(i)], self.camera.with_focal(focal[i]), img[i], level)
            if found is not None:
                return found
        return None

    def _confirm(self, rot, camera, pattern_img, level) -> Candidate | None:
        """Verify in two steps: a loose radius to find matches, a fit, then the tight radius."""
        n = min(len(self.x), self.options.verify_stars)
        proj = project_catalog(self.db, rot, camera, level_bit=level)
        img_i, cat_i = match_nearest(self.x[:n], self.y[:n], proj.x, proj.y, LOOSE_RADIUS_FACTOR * self.radius)
        if np.count_nonzero(~np.isin(img_i, pattern_img)) < MIN_EXTRA_MATCHES:
            return None
        ref = self.db.vectors[proj.star[cat_i]]
        rot, camera, _ = refine_pointing(rot, camera, ref, self.x[img_i], self.y[img_i], fit_focal=self.fit_focal)
        proj = project_catalog(self.db, rot, camera, level_bit=level)
        img_i, cat_i = match_nearest(self.x[:n], self.y[:n], proj.x, proj.y, self.radius)
        extra = ~np.isin(img_i, pattern_img)
        prob = false_match_probability(int(extra.sum()), n - 4, proj.star.size, self.radius,
                                       camera.width, camera.height, self.trials)
        if prob > self.options.max_false_match_prob:
            return None
        return Candidate(rot, camera, img_i, proj.star[cat_i], prob)


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
    deadline = time.perf_counter() + options.timeout_s
    for quad in pattern_order(min(len(x), options.pattern_stars)):
        found = search.try_pattern(quad)
        if found is not None:
            return MatchOutcome(Status.OK, "", found, search.trials)
        if time.perf_counter() > deadline:
            return MatchOutcome(Status.TIMEOUT, f"no match within the {options.timeout_s:g} s time limit",
                                None, search.trials)
    return MatchOutcome(Status.NO_MATCH, f"no pattern of the {min(len(x), options.pattern_stars)} brightest "
                        f"stars matched the catalog with a false-match probability below "
                        f"{options.max_false_match_prob:g} ({search.trials} candidates tried)", None, search.trials)
