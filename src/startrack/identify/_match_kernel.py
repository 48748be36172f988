"""The compiled loops of :mod:`._refine` that pair stars (numba): the final fit's re-match
(projection, image test and closest-first pairing), its choice of catalog stars in a cone, the
confirmation's cone of verification stars (:func:`band_cone`), and the inversion of the lens
model (pixels to unit camera vectors). The projection model is
:func:`.pose_kernel._project` (Brown-Conrady, ``dist`` = (k1, k2, k3, p1, p2)).

Kept apart from startrack's import as :mod:`._pose_kernel` is; compiled functions are cached on
disk (``cache=True``); all arrays are float64 and C-contiguous.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._pose_kernel import _project, _times


@njit(cache=True)
def rematch_pairs(vectors, matrix, fx, fy, cx, cy, dist, width, height, x, y, radius_px):
    """Image stars matched to catalog stars, each used once, closest pairs first (as
    :func:`.verify.match_nearest` on the catalog stars predicted inside the image).

    ``vectors`` (S, 3) are ICRS unit vectors, ``matrix`` (3, 3) takes them to camera vectors; the
    camera has focal lengths ``fx``, ``fy``, principal point ``cx``, ``cy`` (pixels), distortion
    ``dist`` (5,) and a ``width`` x ``height`` image (pixel centres 0 ... width - 1, edges at
    -0.5 and width - 0.5, as :meth:`startrack.camera.Camera.in_image`). ``x``, ``y`` (N,) are the
    image stars (pixels). Returns (image index (K,), catalog index into ``vectors`` (K,)),
    closest pair first; only pairs within ``radius_px`` are formed.
    """
    px, py, inside = _predicted(vectors, matrix, fx, fy, cx, cy, dist, width, height)
    out_i, out_c, _ = _closest_pairs(x, y, px, py, inside, radius_px)
    return out_i, out_c


@njit(cache=True)
def predicted_pairs(vectors, matrix, fx, fy, cx, cy, dist, width, height, x, y, radius_px):
    """:func:`rematch_pairs` with what a false-match test also needs: (image index (K,), catalog
    index into ``vectors`` (K,), squared distance of each pair (K,) in px^2, and the number of
    catalog stars predicted inside the image). The pairs a match within a smaller radius r would
    keep are those of these with a squared distance of at most r * r, in the same order (the
    greedy match takes the closest pairs first)."""
    px, py, inside = _predicted(vectors, matrix, fx, fy, cx, cy, dist, width, height)
    out_i, out_c, out_d2 = _closest_pairs(x, y, px, py, inside, radius_px)
    return out_i, out_c, out_d2, inside.size


@njit(cache=True)
def _predicted(vectors, matrix, fx, fy, cx, cy, dist, width, height):
    """Pixel positions (M,) each of the catalog stars (``vectors`` (S, 3), see
    :func:`rematch_pairs`) that land inside the image, and their indices into ``vectors`` (M,)."""
    s = vectors.shape[0]
    px, py, inside = np.empty(s), np.empty(s), np.empty(s, np.int64)
    m = 0
    for c in range(s):
        v0, v1, v2 = _times(matrix, vectors, c)
        if not v2 > 0.0:
            continue  # behind the image plane
        inv_z = 1.0 / v2
        _, _, ad, bd, _, _, _, _ = _project(v0 * inv_z, v1 * inv_z, 1.0, dist)
        u, w = cx + fx * ad, cy + fy * bd
        if u >= -0.5 and w >= -0.5 and u <= width - 0.5 and w <= height - 0.5:
            px[m], py[m], inside[m] = u, w, c
            m += 1
    return px[:m], py[:m], inside[:m]


@njit(cache=True)
def _closest_pairs(x, y, px, py, index, radius_px):
    """Greedy closest-first pairs (each star once) between image stars ``x``, ``y`` (N,) and
    predicted stars ``px``, ``py`` (M,) within ``radius_px``: (image index, ``index`` of the
    predicted star, squared distance (px^2)), formed in (image, predicted) order and sorted
    stably by distance."""
    r2 = radius_px * radius_px
    k = 0
    for _ in range(2):  # count the pairs, then fill them in
        pi, pc, pd = np.empty(k, np.int64), np.empty(k, np.int64), np.empty(k)
        k = 0
        for i in range(x.size):
            xi, yi = x[i], y[i]
            for j in range(px.size):
                dx, dy = xi - px[j], yi - py[j]
                d2 = dx * dx + dy * dy
                if d2 <= r2:
                    if k < pi.size:
                        pi[k], pc[k], pd[k] = i, j, d2
                    k += 1
    order = _stable_order(pd)
    taken_i, taken_c = np.zeros(x.size, np.bool_), np.zeros(px.size, np.bool_)
    out_i, out_c, out_d2 = np.empty(k, np.int64), np.empty(k, np.int64), np.empty(k)
    n = 0
    for o in order:
        i, j = pi[o], pc[o]
        if not taken_i[i] and not taken_c[j]:
            taken_i[i] = True
            taken_c[j] = True
            out_i[n], out_c[n], out_d2[n] = i, index[j], pd[o]
            n += 1
    return out_i[:n], out_c[:n], out_d2[:n]


@njit(cache=True)
def _stable_order(values):
    """Indices that sort ``values`` (K,) ascending, ties in their order (insertion sort: the few
    pairs of a re-match; ``np.argsort(kind="mergesort")`` would give the same, at seconds of
    compilation more)."""
    order = np.arange(values.size)
    for i in range(1, values.size):
        k, v = order[i], values[order[i]]
        j = i - 1
        while j >= 0 and values[order[j]] > v:
            order[j + 1] = order[j]
            j -= 1
        order[j + 1] = k
    return order

@njit(cache=True)
def cone_stars(vectors, count, axis, cos_reach, neighbour_rad, min_neighbour_rad):
    """Indices (ascending) among the first ``count`` rows of ``vectors`` (S, 3; unit) of those
    whose dot product with the unit vector ``axis`` (3,) is at least ``cos_reach`` and whose
    ``neighbour_rad`` (S,) is at least ``min_neighbour_rad``."""
    out = np.empty(count, np.int64)
    n = 0
    for i in range(count):
        dot = vectors[i, 0] * axis[0] + vectors[i, 1] * axis[1] + vectors[i, 2] * axis[2]
        if dot >= cos_reach and neighbour_rad[i] >= min_neighbour_rad:
            out[n] = i
            n += 1
    return out[:n]

@njit(cache=True)
def band_cone(sorted_vectors, order, z_sorted, sector_starts, axis, chord):
    """Indices (ascending, into the unsorted vectors) of the unit vectors within the chord
    ``chord`` of the unit vector ``axis`` (3,): |v - axis|^2 <= chord^2, the test of
    ``cKDTree.query_ball_point``. The vectors are given in sectors of longitude, each in ascending
    order of z (:class:`.verify.SkyBands`): ``sorted_vectors`` (S, 3), their z ``z_sorted`` (S,),
    their indices ``order`` (S,), and the first position of each of the K sectors
    ``sector_starts`` (K + 1,). Only the sectors the cone can reach are read, and in each the
    band of z within the chord of the axis' (:func:`_scan_ranges`)."""
    ranges = _scan_ranges(z_sorted, sector_starts, axis, chord)
    out = np.empty(_total(ranges), np.int64)
    c2 = chord * chord
    n = 0
    for r in range(ranges.shape[0]):
        for k in range(ranges[r, 0], ranges[r, 1]):
            d0, d1 = sorted_vectors[k, 0] - axis[0], sorted_vectors[k, 1] - axis[1]
            d2 = sorted_vectors[k, 2] - axis[2]
            if d0 * d0 + d1 * d1 + d2 * d2 <= c2:
                out[n] = order[k]
                n += 1
    return np.sort(out[:n])


@njit(cache=True)
def band_cone_stars(vectors, sorted_vectors, order, z_sorted, sector_starts, count, axis, cos_reach, neighbour_rad,
                    neighbour_sorted, min_neighbour_rad):
    """:func:`cone_stars` on ``vectors`` (S, 3), also given as in :func:`band_cone`
    (``neighbour_sorted`` is ``neighbour_rad`` in the order of ``sorted_vectors``): the same
    indices (ascending, those below ``count`` whose dot product with ``axis`` is at least
    ``cos_reach``, computed alike, and whose ``neighbour_rad`` (S,) is at least
    ``min_neighbour_rad``), reading only the sectors and bands of z that such a vector can lie
    in (within the chord sqrt(2 - 2 cos_reach)), or the first ``count`` vectors when they are
    fewer. The pass has no branch (a test that fails half the time at random costs a
    misprediction each)."""
    ranges = _scan_ranges(z_sorted, sector_starts, axis, math.sqrt(max(0.0, 2.0 - 2.0 * cos_reach)))
    total = _total(ranges)
    if total >= count:
        return cone_stars(vectors, count, axis, cos_reach, neighbour_rad, min_neighbour_rad)
    out = np.empty(total, np.int64)
    n = 0
    for r in range(ranges.shape[0]):
        for k in range(ranges[r, 0], ranges[r, 1]):
            i = order[k]
            dot = sorted_vectors[k, 0] * axis[0] + sorted_vectors[k, 1] * axis[1] + sorted_vectors[k, 2] * axis[2]
            keep = (i < count) & (dot >= cos_reach) & (neighbour_sorted[k] >= min_neighbour_rad)
            out[n] = i
            n += 1 if keep else 0
    return np.sort(out[:n])


@njit(cache=True)
def _scan_ranges(z_sorted, sector_starts, axis, chord):
    """Positions [start, stop) (R, 2) to read for the vectors within ``chord`` of ``axis``: in each
    sector of longitude the cone reaches, the values of z within the chord of the axis' (padded
    by 1e-9; the test itself is exact). A cone around axis colatitude t of angular radius p
    spans longitudes within asin(sin p / sin t) of the axis' when it holds no pole; else all."""
    sectors = sector_starts.size - 1
    rho = 2.0 * math.asin(min(1.0, 0.5 * chord))
    colat = math.acos(max(-1.0, min(1.0, axis[2])))
    first, last = 0, sectors - 1
    if rho + 1e-6 < colat and rho + 1e-6 < math.pi - colat:
        half = math.asin(min(1.0, math.sin(rho) / math.sin(colat))) + 1e-6
        lon = math.atan2(axis[1], axis[0])
        first = int(math.floor((lon - half + math.pi) / (2.0 * math.pi) * sectors))
        last = int(math.floor((lon + half + math.pi) / (2.0 * math.pi) * sectors))
        if last - first + 1 >= sectors:
            first, last = 0, sectors - 1
    out = np.empty((last - first + 1, 2), np.int64)
    pad = 1e-9
    for j in range(first, last + 1):
        sector = j % sectors
        lo, hi = sector_starts[sector], sector_starts[sector + 1]
        part = z_sorted[lo:hi]
        out[j - first, 0] = lo + np.searchsorted(part, axis[2] - chord - pad)
        out[j - first, 1] = lo + np.searchsorted(part, axis[2] + chord + pad, side="right")
    return out


@njit(cache=True)
def _total(ranges):
    """How many positions the ranges (R, 2) of :func:`_scan_ranges` hold."""
    total = 0
    for r in range(ranges.shape[0]):
        total += ranges[r, 1] - ranges[r, 0]
    return total


@njit(cache=True, error_model="numpy")  # a zero determinant gives inf / NaN (a NaN point), not an exception
def pixel_vectors(x, y, fx, fy, cx, cy, dist, tol, max_iter):
    """Unit camera vectors (N, 3) of pixels ``x``, ``y`` (N,) with the distortion removed, as
    :meth:`startrack.camera.Camera.pixel_to_vector` computes them: Newton's method on the pinhole
    coordinates of all points together, at most ``max_iter`` steps, until every distorted point
    is within ``tol`` (pinhole units) of the measured one; a point that is not then (beyond the
    fold of the lens polynomial) is NaN."""
    n = x.size
    ad, bd = (x - cx) / fx, (y - cy) / fy
    a, b, ra, rb = ad.copy(), bd.copy(), np.empty(n), np.empty(n)
    for _ in range(max_iter):
        done = True
        for i in range(n):
            _, _, fa, fb, _, _, _, _ = _project(a[i], b[i], 1.0, dist)
            ra[i], rb[i] = fa - ad[i], fb - bd[i]
            done = done and math.hypot(ra[i], rb[i]) < tol
        if done:
            break
        for i in range(n):
            _, _, _, _, daa, dab, dba, dbb = _project(a[i], b[i], 1.0, dist)
            det = daa * dbb - dab * dba
            a[i], b[i] = a[i] - (dbb * ra[i] - dab * rb[i]) / det, b[i] - (-dba * ra[i] + daa * rb[i]) / det
    out = np.empty((n, 3))
    for i in range(n):
        _, _, fa, fb, _, _, _, _ = _project(a[i], b[i], 1.0, dist)
        if not math.hypot(fa - ad[i], fb - bd[i]) < tol:
            out[i, 0] = out[i, 1] = out[i, 2] = np.nan
            continue
        norm = math.sqrt(a[i] * a[i] + b[i] * b[i] + 1.0)
        out[i, 0], out[i, 1], out[i, 2] = a[i] / norm, b[i] / norm, 1.0 / norm
    return out
