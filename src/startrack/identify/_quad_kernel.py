"""The compiled loop of :mod:`._quad_search` (numba): steps 1-4 of its docstring, per pattern.

Kept apart so that importing startrack does not import numba; :func:`.quad_search.search_batch`
loads this module on first use. Compiled functions are cached on disk (``cache=True``), so the
compilation (a few seconds) happens once per installation, loading the cache once per process.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._database import KEY_BINS, LARGEST_LN_MIN, LARGEST_LN_STEP, LEVEL_SHIFT, RATIO_SCALE
from ._patterns import EDGE_PAIRS, PERMUTATIONS, PERMUTED_EDGES
from ._pose_kernel import q_method

COARSE_STRIDE = 8
"""Grid points between the evaluations of a pattern's ratios when its trials are chosen."""

DISTORTION_SHAPE_CAP = 0.01
"""The lens term of a look-up tolerance stops at this relative stretch: beyond it a pattern's box
holds so many random catalog patterns that confirming them costs more than a lens that bends
that much is worth (measured in ``docs/identification.md``); such lenses are matched from the
patterns near the image centre."""

FITTED_FOCAL_STEP_SHARE = 0.25
"""Share of the focal step kept in the rotation-fit tolerance once the focal length is corrected."""

_EDGE_I = np.ascontiguousarray(EDGE_PAIRS[:, 0])
_EDGE_J = np.ascontiguousarray(EDGE_PAIRS[:, 1])
_PERMUTATIONS = np.ascontiguousarray(PERMUTATIONS)
_PERMUTED_EDGES = np.ascontiguousarray(PERMUTED_EDGES)


@njit(cache=True)
def _angle(a, b) -> float:
    """Angle (radians) between 3-vectors a and b, by the stable atan2 form."""
    cx = a[1] * b[2] - a[2] * b[1]
    cy = a[2] * b[0] - a[0] * b[2]
    cz = a[0] * b[1] - a[1] * b[0]
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), a[0] * b[0] + a[1] * b[1] + a[2] * b[2])


@njit(cache=True)
def _image_vectors(u, w, stars, scale, out) -> None:
    """Unit vectors (4, 3) of the image stars ``stars`` (4,) at ``scale`` = f_nominal / f."""
    for i in range(4):
        a, b = u[stars[i]] * scale, w[stars[i]] * scale
        norm = math.sqrt(a * a + b * b + 1.0)
        out[i, 0], out[i, 1], out[i, 2] = a / norm, b / norm, 1.0 / norm


@njit(cache=True)
def _edges(vec, angles) -> None:
    """The six pair angles (radians, :data:`EDGE_PAIRS` order) of four unit vectors (4, 3)."""
    for e in range(6):
        angles[e] = _angle(vec[_EDGE_I[e]], vec[_EDGE_J[e]])


@njit(cache=True)
def _sorted_ratios(angles, ordered, ratios) -> float:
    """Sort the six angles into ``ordered``, write the five ratios to the largest; return it."""
    for e in range(6):
        ordered[e] = angles[e]
    for i in range(1, 6):
        value, j = ordered[i], i - 1
        while j >= 0 and ordered[j] > value:
            ordered[j + 1] = ordered[j]
            j -= 1
        ordered[j + 1] = value
    for k in range(5):
        ratios[k] = ordered[k] / ordered[5]
    return ordered[5]


@njit(cache=True)
def _ratio_change(u, w, quad, scale, vec, angles, ordered, ratios, previous) -> float:
    """Largest change of the five edge ratios from ``previous`` to their values at ``scale``
    (which then replace ``previous``)."""
    _image_vectors(u, w, quad, scale, vec)
    _edges(vec, angles)
    _sorted_ratios(angles, ordered, ratios)
    change = 0.0
    for k in range(5):
        change = max(change, abs(ratios[k] - previous[k]))
        previous[k] = ratios[k]
    return change


@njit(cache=True)
def _trial_starts(u, w, quad, grid, step, vec, angles, ordered, ratios, starts):
    """Grid indices where the pattern's trials start (step 1 of the module docstring).

    The ratios are evaluated at every :data:`COARSE_STRIDE`-th grid point and their change is
    spread evenly over the points between (the ratios are smooth in the scale); a trial starts
    wherever the accumulated change passes a multiple of the focal step."""
    size = grid.size
    starts[0] = 0
    if size == 1:
        return starts[:1]
    previous = np.zeros(5)
    _ratio_change(u, w, quad, grid[0], vec, angles, ordered, ratios, previous)
    total, group, count, g0 = 0.0, 0, 1, 0
    while g0 < size - 1:
        g1 = min(g0 + COARSE_STRIDE, size - 1)
        change = _ratio_change(u, w, quad, grid[g1], vec, angles, ordered, ratios, previous)
        for g in range(g0 + 1, g1 + 1):
            new_group = math.floor((total + change * (g - g0) / (g1 - g0)) / step)
            if new_group != group:
                starts[count] = g
                count += 1
                group = new_group
        total += change
        g0 = g1
    return starts[:count]


@njit(cache=True)
def ratio_tolerances(ordered, ratios, step, noise_px, focal_px, shape, tol) -> float:
    """Tolerance of each of the five edge ratios (step 2); writes ``tol`` (5,), returns the largest.

    ``ordered`` (6,) are the sorted edge angles (radians), ``ratios`` (5,) the first five over the
    largest, ``noise_px`` the error bound of one edge length (pixels), ``focal_px`` the trial's
    focal length, ``shape`` the bound on the relative change of one edge against another that
    the lens may cause (:func:`shape_bound`). A ratio r = a / b of edges a <= b measured with
    errors da, db moves by da / b - r db / b, so its bound is step + noise (1 + r) / b, with b in
    pixels; a lens that stretches a by a fraction s more than b moves it by r s more."""
    largest_px = ordered[5] * focal_px
    for k in range(5):
        tol[k] = step + noise_px * (1.0 + ratios[k]) / largest_px + shape * ratios[k]
    return tol.max()


@njit(cache=True)
def radius2_range(u, w, quad, scale):
    """Smallest and largest squared pinhole radius (a^2 + b^2) of the pattern's four stars at ``scale``."""
    lo, hi = np.inf, 0.0
    for i in range(4):
        r2 = (u[quad[i]] * u[quad[i]] + w[quad[i]] * w[quad[i]]) * scale * scale
        lo, hi = min(lo, r2), max(hi, r2)
    return lo, hi


@njit(cache=True)
def shape_bound(distortion, r2_lo, r2_hi) -> float:
    """Bound on the relative stretch of one pattern edge against another by a radial distortion
    r -> r (1 + k1 r^2) with |k1| <= ``distortion``, for stars at squared pinhole radii
    ``r2_lo`` .. ``r2_hi``: an edge there is scaled by between 1 + k1 r^2 (across the radius) and
    1 + 3 k1 r^2 (along it), so two edges differ by at most |k1| (3 r2_hi - r2_lo)."""
    return distortion * (3.0 * r2_hi - r2_lo)


@njit(cache=True)
def _bin(quantised: int) -> int:
    return (quantised * KEY_BINS) >> 16


@njit(cache=True)
def _quantise(value: float) -> int:
    """Ratio to stored units, rounded half to even as numpy does, clipped to [0, RATIO_SCALE]."""
    return int(min(max(np.rint(value * RATIO_SCALE), 0.0), RATIO_SCALE))


@njit(cache=True)
def _floor_q(value: float) -> int:
    """Ratio to stored units, rounded down, clipped to [0, 1] first."""
    return int(math.floor(min(max(value, 0.0), 1.0) * RATIO_SCALE))


@njit(cache=True)
def _lower_bound(keys, lo, hi, value) -> int:
    """numpy.searchsorted of one value (side 'left') in ``keys[lo:hi]``, as an index into keys."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if keys[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


LARGEST_EDGE_SLACK = 0.95
"""A level holds patterns whose largest edge is up to its region's diameter over this (a region
is a circle of radius ``region_fraction`` times the level's field of view)."""


@njit(cache=True)
def _level_fits(level_fov, level_ratio, region_fraction, fov_lo, fov_hi, largest) -> bool:
    """Whether a level serves a trial's range of fields of view and holds patterns this large."""
    return (level_fov >= fov_lo / level_ratio and level_fov <= fov_hi * level_ratio
            and 2.0 * region_fraction * level_fov >= LARGEST_EDGE_SLACK * largest)


@njit(cache=True)
def widest_level_fov(level_fovs, level_ratio, fov_lo, fov_hi) -> float:
    """The widest level field of view (radians) within the window of :func:`_level_fits` for
    fields of view from ``fov_lo`` to ``fov_hi``; 0 when no level lies in it."""
    widest = 0.0
    for fov in level_fovs:
        if fov_lo / level_ratio <= fov <= fov_hi * level_ratio:
            widest = max(widest, fov)
    return widest


@njit(cache=True)
def _wider_than(u, w, quad, scale_lo, scale_hi, cos_limit, vec_lo, vec_hi) -> bool:
    """Whether some edge of the pattern spans more than the angle whose cosine is ``cos_limit``
    at every scale from ``scale_lo`` to ``scale_hi``: then no level can hold the pattern at any
    of its trials, and the search skips it before choosing them. An edge's angle has no
    interior minimum over a range of scales (it grows, or grows then shrinks, with the scale:
    the angle a segment subtends from a point moving along a line), so it is enough that it
    exceeds the limit at both ends; compared by cosines (no arctangent)."""
    _image_vectors(u, w, quad, scale_lo, vec_lo)
    _image_vectors(u, w, quad, scale_hi, vec_hi)
    for e in range(6):
        i, j = _EDGE_I[e], _EDGE_J[e]
        cos_lo = vec_lo[i, 0] * vec_lo[j, 0] + vec_lo[i, 1] * vec_lo[j, 1] + vec_lo[i, 2] * vec_lo[j, 2]
        cos_hi = vec_hi[i, 0] * vec_hi[j, 0] + vec_hi[i, 1] * vec_hi[j, 1] + vec_hi[i, 2] * vec_hi[j, 2]
        if max(cos_lo, cos_hi) < cos_limit:
            return True
    return False


@njit(cache=True)
def _ratios_fit(stored, low, high) -> bool:
    """Whether all five stored ratios lie within [low, high] (stored units)."""
    for k in range(5):
        if stored[k] < low[k] or stored[k] > high[k]:
            return False
    return True


@njit(cache=True)
def _best_order(img_angles, cat_angles):
    """(ordering index, misfit (rad), edge-sum scale) of the best of the 24 star orderings."""
    scale = cat_angles.sum() / img_angles.sum()
    best, best_misfit = 0, np.inf
    for p in range(24):
        misfit = 0.0
        for e in range(6):
            misfit = max(misfit, abs(img_angles[_PERMUTED_EDGES[p, e]] * scale - cat_angles[e]))
        if misfit < best_misfit:
            best, best_misfit = p, misfit
    return best, best_misfit, scale


@njit(cache=True)
def _worst_residual(rot, obs, ref) -> float:
    """Largest angle (radians) between the rotated reference vectors and the observed ones (4, 3)."""
    worst, predicted = 0.0, np.empty(3)
    for i in range(4):
        for j in range(3):
            predicted[j] = rot[j, 0] * ref[i, 0] + rot[j, 1] * ref[i, 1] + rot[j, 2] * ref[i, 2]
        worst = max(worst, _angle(predicted, obs[i]))
    return worst


@njit(cache=True)
def _grow(quats, focal, stars, row, count):
    """The output arrays with twice the room, the first ``count`` entries kept."""
    size = 2 * max(count, 8)
    q2, f2, s2, r2 = np.empty((size, 4)), np.empty(size), np.empty((size, 4), np.int64), np.empty(size, np.int64)
    q2[:count], f2[:count], s2[:count], r2[:count] = quats[:count], focal[:count], stars[:count], row[:count]
    return q2, f2, s2, r2


@njit(cache=True)
def _matching_rows(keys, cell_starts, pattern_ratios, pattern_largest, level_fovs, level_ratio, region_fraction,
                   ratios, tol, largest, trial_focal, fov_lo, fov_hi, window_lo, window_hi, rows, low, high):
    """Database rows whose key, five ratios and implied focal length fit one trial (step 3).

    Writes them to ``rows`` (grown when full) and returns (rows, count); ``low``, ``high`` (5,)
    are work space for the ratio bounds.
    """
    for k in range(5):
        low[k], high[k] = np.rint((ratios[k] - tol[k]) * RATIO_SCALE), np.rint((ratios[k] + tol[k]) * RATIO_SCALE)
    b0_lo, b0_hi = _bin(_floor_q(ratios[0] - tol[0])), _bin(_floor_q(ratios[0] + tol[0]))
    b1_lo, b1_hi = _bin(_floor_q(ratios[1] - tol[1])), _bin(_floor_q(ratios[1] + tol[1]))
    r2_lo, r2_hi = _quantise(ratios[2] - tol[2]), _quantise(ratios[2] + tol[2])
    count = 0
    for level in range(level_fovs.size):
        if not _level_fits(level_fovs[level], level_ratio, region_fraction, fov_lo, fov_hi, largest):
            continue
        for b0 in range(b0_lo, b0_hi + 1):
            for b1 in range(b1_lo, b1_hi + 1):
                cell = (level * KEY_BINS + b0) * KEY_BINS + b1
                lo, hi = cell_starts[cell], cell_starts[cell + 1]
                base = (level << LEVEL_SHIFT) + (b0 * KEY_BINS + b1) * 65536
                top = base + r2_hi
                for r in range(_lower_bound(keys, lo, hi, base + r2_lo), hi):  # keys ascend in a cell
                    if keys[r] > top:
                        break
                    if not _ratios_fit(pattern_ratios[r], low, high):
                        continue
                    implied = trial_focal * largest / math.exp(LARGEST_LN_MIN + pattern_largest[r] * LARGEST_LN_STEP)
                    if window_lo <= implied <= window_hi:
                        if count == rows.size:
                            rows = np.concatenate((rows, np.empty(rows.size, np.int64)))
                        rows[count] = r
                        count += 1
    return rows, count


@njit(cache=True)
def _fit_order(u, w, quad, order, scale, cat_vec, stars, obs):
    """Rotation (quaternion (4,), matrix (3, 3)) of one candidate under star ordering ``order`` at ``scale`` (step 4).

    Writes the image star of each catalog star to ``stars`` (4,) and their vectors to ``obs`` (4, 3).
    """
    for i in range(4):
        stars[i] = quad[_PERMUTATIONS[order, i]]
    _image_vectors(u, w, stars, scale, obs)
    return q_method(obs, cat_vec)


@njit(cache=True)
def _largest_edge_cos(grid, focal_nominal, short_px, square_px, level_fovs, level_ratio, region_fraction) -> float:
    """Cosine of the largest edge (a bit beyond it) that :func:`_level_fits` lets any trial of
    the grid look up: the region diameter of the widest level the grid's window reaches over
    :data:`LARGEST_EDGE_SLACK`; -2 (no edge exceeds it) when that reaches half a turn."""
    fov_lo = 2.0 * math.atan(short_px * grid[0] / (2.0 * focal_nominal))
    fov_hi = 2.0 * math.atan(square_px * grid[grid.size - 1] / (2.0 * focal_nominal))
    limit = 2.0 * region_fraction * widest_level_fov(level_fovs, level_ratio, fov_lo, fov_hi) / LARGEST_EDGE_SLACK
    return math.cos(limit * (1.0 + 1e-9)) if limit * (1.0 + 1e-9) < math.pi else -2.0


@njit(cache=True)
def search(u, w, quads, grid, focal_nominal, short_px, square_px, sigma_px, step, max_tolerance, fit_focal,
           distortion, shape_floor, level_fovs, level_ratio, region_fraction, keys, cell_starts, pattern_ratios,
           pattern_largest, pattern_stars, vectors, first):
    """The compiled loop of :func:`.quad_search.search_batch` (steps 1-4 of the module docstring),
    from pattern ``first`` up to and including the first pattern that yields a candidate; also
    returns the index of the pattern after the last one searched. ``distortion`` bounds |k1| of
    an uncalibrated lens (0: none), which widens the tolerances (:func:`shape_bound`);
    ``shape_floor`` is a relative edge stretch allowed everywhere (a pixel aspect known to
    +-``shape_floor``)."""
    vec, cat_vec, obs = np.empty((4, 3)), np.empty((4, 3)), np.empty((4, 3))
    angles, cat_angles, ordered, ratios, tol = np.empty(6), np.empty(6), np.empty(6), np.empty(5), np.empty(5)
    quad, stars, rows = np.empty(4, np.int64), np.empty(4, np.int64), np.empty(64, np.int64)
    low, high, starts_buffer = np.empty(5), np.empty(5), np.empty(grid.size, np.int64)
    quats, focal, out_stars, out_row = _grow(np.empty((0, 4)), np.empty(0), np.empty((0, 4), np.int64),
                                             np.empty(0, np.int64), 0)
    count, n_tried = 0, 0
    noise = 3.0 * sigma_px * math.sqrt(2.0)
    step_share = FITTED_FOCAL_STEP_SHARE if fit_focal else 1.0
    cos_limit = _largest_edge_cos(grid, focal_nominal, short_px, square_px, level_fovs, level_ratio, region_fraction)
    for p in range(first, quads.shape[0]):
        quad[:] = quads[p]
        if _wider_than(u, w, quad, grid[0], grid[grid.size - 1], cos_limit, vec, obs):
            continue  # no level holds it at any trial (_level_fits)
        starts = _trial_starts(u, w, quad, grid, step, vec, angles, ordered, ratios, starts_buffer)
        for t in range(starts.size):
            scale = grid[starts[t]]
            scale_hi = grid[starts[t + 1]] if t + 1 < starts.size else grid[grid.size - 1]
            _image_vectors(u, w, quad, scale, vec)
            _edges(vec, angles)
            largest = _sorted_ratios(angles, ordered, ratios)
            trial_focal = focal_nominal / scale
            r2_lo, r2_hi = radius2_range(u, w, quad, scale)
            shape = shape_floor + min(DISTORTION_SHAPE_CAP, shape_bound(distortion, r2_lo, r2_hi))
            worst_tol = ratio_tolerances(ordered, ratios, step, noise, trial_focal, shape, tol)
            if worst_tol > max_tolerance:
                continue
            fov_lo = 2.0 * math.atan(short_px * scale / (2.0 * focal_nominal))
            fov_hi = 2.0 * math.atan(square_px * scale_hi / (2.0 * focal_nominal))
            stretch = min(0.5, shape_floor + 3.0 * distortion * r2_hi)  # the lens may lengthen the largest edge
            rows, n_rows = _matching_rows(keys, cell_starts, pattern_ratios, pattern_largest, level_fovs, level_ratio,
                                          region_fraction, ratios, tol, largest, trial_focal, fov_lo, fov_hi,
                                          focal_nominal / scale_hi * 0.98 * (1.0 - stretch),
                                          trial_focal * 1.02 * (1.0 + stretch), rows, low, high)
            for j in range(n_rows):
                r = rows[j]
                for i in range(4):
                    cat_vec[i] = vectors[pattern_stars[r, i]]
                _edges(cat_vec, cat_angles)
                order, misfit, edge_scale = _best_order(angles, cat_angles)
                if misfit > 3.0 * worst_tol * cat_angles.max():
                    continue
                n_tried += 1
                fitted = scale * edge_scale if fit_focal else scale
                quat, rot = _fit_order(u, w, quad, order, fitted, cat_vec, stars, obs)
                f = focal_nominal / fitted
                if _worst_residual(rot, obs, cat_vec) > 6.0 * sigma_px / f + (step_share * step + shape) * largest:
                    continue
                if count == focal.size:
                    quats, focal, out_stars, out_row = _grow(quats, focal, out_stars, out_row, count)
                quats[count], focal[count], out_stars[count], out_row[count] = quat, f, stars, r
                count += 1
        if count > 0:
            return quats[:count], focal[:count], out_stars[:count], out_row[:count], n_tried, p + 1
    return quats[:count], focal[:count], out_stars[:count], out_row[:count], n_tried, quads.shape[0]
