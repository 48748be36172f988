"""Batched look-up of four-star patterns: many image patterns and trial focal lengths at once.

The steps of :mod:`.quad_matcher` for a whole batch of image patterns, as array operations:

1. :func:`focal_trials` - per pattern, the trial focal lengths (scales f_nominal / f) whose edge
   ratios differ by more than the tolerance;
2. :func:`trial_geometry` - edge angles, ratios and tolerances of every (pattern, trial);
3. :func:`candidate_rows` - the database levels each trial may match, the key range
   queries per bin of the smallest ratio, and the ratio and scale filters;
4. :func:`fit_candidates` - the star correspondence from the edges, the rotation (q-method) and
   the residual test.

Everything is ordered pattern-major, so candidates come out in the order the patterns were
formed (brightest stars first).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..attitude.qmethod import q_method_quaternions
from ..frames import angle_between
from .database import KEY_BINS, RATIO_SCALE, PatternDatabase, ratio_bin
from .patterns import PERMUTATIONS, PERMUTED_EDGES, edge_ratios, pair_angles

FITTED_FOCAL_STEP_SHARE = 0.25
"""Share of the focal step kept in the rotation-fit tolerance once the focal length is corrected."""

FOCAL_GRID = 48
FOCAL_GRID_SPAN = 7.0
FOCAL_GRID_STEP = 0.004
"""The trials are chosen on a logarithmic grid of focal lengths with FOCAL_GRID points per
factor FOCAL_GRID_SPAN for a ratio step of FOCAL_GRID_STEP, proportionally more for a finer
step (48 points from 5 to 35 deg at 0.004; 3 for a FOV known to a few percent)."""


def pattern_vectors(u: NDArray, w: NDArray, scale: NDArray) -> NDArray:
    """Unit vectors (..., 3) of normalised coordinates (u, w) scaled by ``scale`` = f_nominal / f.

    ``u`` and ``w`` broadcast against ``scale[..., None]``.
    """
    s = np.asarray(scale)[..., None]
    us, ws = u * s, w * s
    v = np.stack([us, ws, np.ones_like(us)], axis=-1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@dataclass(frozen=True)
class Trials:
    """Trial focal lengths of a batch of patterns, pattern-major.

    Attributes (all shape (T,) unless noted): ``pattern`` index into the batch, ``scale`` and the
    interval ``[scale_lo, scale_hi]`` it stands for.
    """

    pattern: NDArray[np.int64]
    scale: NDArray[np.float64]
    scale_lo: NDArray[np.float64]
    scale_hi: NDArray[np.float64]


def focal_trials(u: NDArray, w: NDArray, scale_range: tuple[float, float], step: float) -> Trials:
    """Trial scales per pattern so that its edge ratios change by less than ``step`` within each.

    Parameters
    ----------
    u, w : ndarray, shape (P, 4)
        Normalised pinhole coordinates of the patterns' stars at the nominal focal length.
    scale_range : (float, float)
        Smallest and largest f_nominal / f (equal when the focal length is known).
    step : float
        Largest ratio change a trial may stand for.
    """
    n = u.shape[0]
    lo, hi = scale_range
    if hi <= lo * (1 + 1e-9):
        ones = np.ones(n)
        return Trials(np.arange(n), lo * ones, lo * ones, hi * ones)
    density = FOCAL_GRID * max(1.0, FOCAL_GRID_STEP / step)  # finer steps need a finer grid
    size = max(3, math.ceil(density * math.log(hi / lo) / math.log(FOCAL_GRID_SPAN)))
    grid = np.geomspace(lo, hi, size)
    ratios, _ = edge_ratios(pair_angles(pattern_vectors(u, w, grid[:, None])))  # (G, P, 5)
    change = np.max(np.abs(np.diff(ratios, axis=0)), axis=-1)  # (G - 1, P)
    group = np.floor(np.vstack([np.zeros((1, n)), np.cumsum(change, axis=0)]) / step)
    starts = np.vstack([np.ones((1, n), bool), group[1:] != group[:-1]]).T  # (P, G), pattern-major
    pattern, g = np.nonzero(starts)
    next_g = np.append(g[1:], size - 1)
    last = np.append(pattern[1:] != pattern[:-1], True)
    end = np.where(last, size - 1, next_g)
    return Trials(pattern, grid[g], grid[g], grid[end])


@dataclass(frozen=True)
class TrialGeometry:
    """Edge angles (T, 6), ratios (T, 5), largest edge (T,), tolerances (T, 5), focal (T,)."""

    angles: NDArray
    ratios: NDArray
    largest: NDArray
    tolerance: NDArray
    focal: NDArray


def trial_geometry(u: NDArray, w: NDArray, trials: Trials, focal_nominal: float, sigma_px: float,
                   focal_step: float) -> TrialGeometry:
    """Pattern geometry at each trial focal length, with its ratio tolerances.

    The tolerance of each ratio adds the focal step to a 3-sigma centroid error propagated into
    the ratio of two edges measured in pixels.
    """
    angles = pair_angles(pattern_vectors(u[trials.pattern], w[trials.pattern], trials.scale))
    ratios, largest = edge_ratios(angles)
    focal = focal_nominal / trials.scale
    edges_px = np.sort(angles, axis=1) * focal[:, None]
    noise = 3.0 * sigma_px * np.sqrt(2.0)
    tolerance = focal_step + noise * (1.0 / edges_px[:, :5] + ratios / edges_px[:, 5:6])
    return TrialGeometry(angles, ratios, largest, tolerance, focal)


def _levels(db: PatternDatabase, trials: Trials, geom: TrialGeometry, focal_nominal: float,
            short_px: int) -> tuple[NDArray, NDArray]:
    """(trial, level) pairs: levels whose scale suits the trial's range of fields of view."""
    fov_lo = 2.0 * np.arctan(short_px * trials.scale_lo / (2.0 * focal_nominal))
    fov_hi = 2.0 * np.arctan(short_px * trials.scale_hi / (2.0 * focal_nominal))
    level_fov = db.level_fov_rad[None, :]
    ratio = db.settings.level_ratio
    fits = (level_fov >= fov_lo[:, None] / ratio) & (level_fov <= fov_hi[:, None] * ratio)
    smallest_largest = geom.largest * trials.scale_lo / trials.scale
    fits &= 2.0 * db.settings.region_fraction * level_fov >= 0.95 * smallest_largest[:, None]
    return np.nonzero(fits)


def _bins(ratio: NDArray, tol: NDArray) -> tuple[NDArray, NDArray]:
    lo = np.floor(np.clip(ratio - tol, 0.0, 1.0) * RATIO_SCALE).astype(np.int64)
    hi = np.floor(np.clip(ratio + tol, 0.0, 1.0) * RATIO_SCALE).astype(np.int64)
    return ratio_bin(lo), ratio_bin(hi)


def _ranges(db: PatternDatabase, geom: TrialGeometry, trial: NDArray, level: NDArray):
    """Key-range queries, one per (trial, level, bin of r0, bin of r1): row ranges and their trial.

    See :func:`startrack.identify.database.pattern_key` for the key.
    """
    r, t = geom.ratios[trial], geom.tolerance[trial]
    b0_lo, b0_hi = _bins(r[:, 0], t[:, 0])
    b1_lo, b1_hi = _bins(r[:, 1], t[:, 1])
    n0, n1 = b0_hi - b0_lo + 1, b1_hi - b1_lo + 1
    count = n0 * n1
    k = _ramp(count)
    q = np.repeat(np.arange(trial.size), count)
    cell = (b0_lo[q] + k // n1[q]) * KEY_BINS + b1_lo[q] + k % n1[q]
    r2_lo = np.clip(np.round((r[:, 2] - t[:, 2]) * RATIO_SCALE), 0, RATIO_SCALE).astype(np.int64)[q]
    r2_hi = np.clip(np.round((r[:, 2] + t[:, 2]) * RATIO_SCALE), 0, RATIO_SCALE).astype(np.int64)[q]
    start, stop = db.key_ranges(level[q], cell * 65536 + r2_lo, cell * 65536 + r2_hi)
    return start, stop, trial[q]


def _ramp(count: NDArray) -> NDArray[np.int64]:
    """0, 1, ..., count[0] - 1, 0, 1, ..., count[1] - 1, ... (ragged aranges)."""
    total = int(count.sum())
    offsets = np.repeat(np.cumsum(count) - count, count)
    return np.arange(total) - offsets


def candidate_rows(db: PatternDatabase, trials: Trials, geom: TrialGeometry, focal_nominal: float,
                   short_px: int, max_tolerance: float) -> tuple[NDArray, NDArray]:
    """Database rows whose ratios and implied focal length fit each trial.

    Returns
    -------
    trial, row : ndarray of int, shape (C,)
        Each candidate's trial and database pattern row, pattern-major.
    """
    usable = np.flatnonzero(geom.tolerance.max(axis=1) <= max_tolerance)
    trial, level = _levels(db, _take(trials, usable), _take_geom(geom, usable), focal_nominal, short_px)
    trial = usable[trial]
    start, stop, q_trial = _ranges(db, geom, trial, level)
    count = stop - start
    row = np.repeat(start, count) + _ramp(count)
    cand_trial = np.repeat(q_trial, count)
    stored = db.pattern_ratios[row]
    q_lo = np.round((geom.ratios - geom.tolerance) * RATIO_SCALE)[cand_trial]
    q_hi = np.round((geom.ratios + geom.tolerance) * RATIO_SCALE)[cand_trial]
    keep = np.all((stored >= q_lo) & (stored <= q_hi), axis=1)
    row, cand_trial = row[keep], cand_trial[keep]
    focal = geom.focal[cand_trial] * geom.largest[cand_trial] / db.largest_rad(row)
    window_lo = focal_nominal / trials.scale_hi[cand_trial] * 0.98
    window_hi = focal_nominal / trials.scale_lo[cand_trial] * 1.02
    keep = (focal >= window_lo) & (focal <= window_hi)
    return cand_trial[keep], row[keep]


def _take(trials: Trials, idx: NDArray) -> Trials:
    return Trials(trials.pattern[idx], trials.scale[idx], trials.scale_lo[idx], trials.scale_hi[idx])


def _take_geom(geom: TrialGeometry, idx: NDArray) -> TrialGeometry:
    return TrialGeometry(geom.angles[idx], geom.ratios[idx], geom.largest[idx], geom.tolerance[idx], geom.focal[idx])


@dataclass(frozen=True)
class Fits:
    """Candidates whose four stars fit a rotation: attitude, focal length, image stars, row."""

    rotation: Rotation | None
    focal: NDArray[np.float64]
    image_stars: NDArray[np.int64]
    row: NDArray[np.int64]
    n_tried: int


def fit_candidates(db: PatternDatabase, u: NDArray, w: NDArray, quads: NDArray, trials: Trials,
                   geom: TrialGeometry, cand_trial: NDArray, row: NDArray, *, focal_nominal: float,
                   fit_focal: bool, sigma_px: float, focal_step: float) -> Fits:
    """Correspondence, rotation and residual test for every candidate (see the module docstring)."""
    cat_vec = db.vectors[db.pattern_stars[row]]  # (C, 4, 3)
    cat_angles = pair_angles(cat_vec)
    img_angles = geom.angles[cand_trial]
    permuted = img_angles[:, PERMUTED_EDGES]  # (C, 24, 6)
    scale = cat_angles.sum(axis=1) / img_angles.sum(axis=1)
    misfit = np.max(np.abs(permuted * scale[:, None, None] - cat_angles[:, None, :]), axis=2)
    best = np.argmin(misfit, axis=1)
    ok = misfit[np.arange(best.size), best] <= 3.0 * geom.tolerance[cand_trial].max(axis=1) * cat_angles.max(axis=1)
    cand_trial, row, best, cat_vec, scale = cand_trial[ok], row[ok], best[ok], cat_vec[ok], scale[ok]
    if row.size == 0:
        return Fits(None, np.zeros(0), np.zeros((0, 4), np.int64), row, 0)
    stars = quads[trials.pattern[cand_trial]][np.arange(row.size)[:, None], PERMUTATIONS[best]]
    scales = trials.scale[cand_trial] * (scale if fit_focal else 1.0)
    obs = pattern_vectors(u[stars], w[stars], scales)
    weights = np.full(obs.shape[:2], 0.25)
    rotation = Rotation.from_quat(q_method_quaternions(obs, cat_vec, weights))
    predicted = np.einsum("cij,ckj->cki", rotation.as_matrix(), cat_vec)
    focal = focal_nominal / scales
    # With the focal length corrected from the edge sums only the centroid noise (and a little of
    # the projection's non-linearity) is left; with it fixed, the trial's focal step remains.
    step_share = FITTED_FOCAL_STEP_SHARE if fit_focal else 1.0
    tol = 6.0 * sigma_px / focal + step_share * focal_step * geom.largest[cand_trial]
    good = np.flatnonzero(np.max(angle_between(predicted, obs), axis=1) <= tol)
    return Fits(rotation[good] if good.size else None, focal[good], stars[good], row[good], int(row.size))
