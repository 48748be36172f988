"""The compiled loops of the detector's whole-frame passes (numba): binning and smoothing of the
detection image, the gathering of tile samples (and of their residuals from the interpolated
level), the 3 x 3 median of a tile grid, the significance image, the fine pass's local contrast (two
smoothings and their difference in one pass) and the 8-connected labelling.

Each loop gives the numbers of the numpy expressions it replaces (the same float32 operations in
the same order), so the detector's results do not depend on which one ran; they are one pass over
the frame each instead of a dozen numpy temporaries. Kept apart so that importing startrack does
not import numba: :mod:`._compiled` loads this module on first use. Compiled functions are cached
on disk (``cache=True``, see :mod:`startrack.numba_cache`); numpy's error model (a division by
zero gives inf or NaN, as in numpy, and the loops vectorize).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def bin_mean(image, factor, out, row, exact):
    """Mean over ``factor`` x ``factor`` blocks as float32, trailing rows and columns dropped:
    each block's rows summed first (in the wider of float32 and the image's type, rounded to
    float32), then its columns, then scaled, as :func:`.smooth.bin_mean` did with numpy.
    ``image`` (H, W) of any real dtype, into float32 ``out`` (H // factor, W // factor); ``row``
    (W // factor * factor,) float32 is the work row (see :func:`smooth`); ``exact``: the image
    holds integers of at most 16 bits, whose float32 sums are exact (added in float32)."""
    h, w = out.shape
    scale = np.float32(1.0 / (factor * factor))
    for i in range(h):
        src = image[i * factor]
        for j in range(w * factor):
            row[j] = src[j]
        for dy in range(1, factor):  # added in the wider of float32 and the image's type
            src = image[i * factor + dy]
            if exact:  # small integers: float32 holds them and their sums exactly
                for j in range(w * factor):
                    row[j] += np.float32(src[j])
            else:
                for j in range(w * factor):
                    row[j] += src[j]
        if factor == 2:
            dst = out[i]
            for j in range(w):
                dst[j] = (row[2 * j] + row[2 * j + 1]) * scale
            continue
        for j in range(w):
            total = row[j * factor]
            for dx in range(1, factor):
                total += row[j * factor + dx]
            out[i, j] = total * scale
    return out


@njit(cache=True, error_model="numpy")
def smooth(image, weights, out, scratch):
    """Separable smoothing of float32 ``image`` (H, W) with the odd float32 ``weights`` (K,),
    edges repeated, into float32 ``out`` (H, W): rows first, then columns, each
    ``sum_k weights[k] * shifted_k`` accumulated in float32 from k = 0 (as
    :func:`.smooth.smooth` did with numpy). Row by row: the first pass of a row goes to
    ``scratch`` (W,), which the caller places away from the rows' addresses modulo 4 KiB (a
    load from an address 4 KiB apart from a pending store waits for it)."""
    h = image.shape[0]
    r = weights.size // 2
    for i in range(h):
        src, first = image[min(max(i - r, 0), h - 1)], weights[0]
        for j in range(scratch.size):
            scratch[j] = src[j] * first
        for k in range(1, weights.size):
            src, weight = image[min(max(i - r + k, 0), h - 1)], weights[k]
            for j in range(scratch.size):
                scratch[j] += weight * src[j]
        _smooth_row(scratch, weights, out[i])
    return out


@njit(cache=True, error_model="numpy")
def _smooth_row(row, weights, out):
    """One row of :func:`smooth`'s second pass: the interior by shifted slices, the ``r``
    pixels at either end with clamped indices."""
    w, r = row.size, weights.size // 2
    lo, hi = min(r, w), max(min(r, w), w - r)
    dst, src, first = out[lo:hi], row[lo - r: hi - r], weights[0]
    for j in range(hi - lo):
        dst[j] = src[j] * first
    for k in range(1, weights.size):
        src, weight = row[lo - r + k: hi - r + k], weights[k]
        for j in range(hi - lo):
            dst[j] += weight * src[j]
    for j in range(lo):
        out[j] = _clamped_sum(row, weights, j)
    for j in range(hi, w):
        out[j] = _clamped_sum(row, weights, j)


@njit(cache=True, error_model="numpy")
def contrast(image, inner, box, out, ring, pads):
    """``a - smooth(a, box weights)`` with ``a = smooth(image, inner)`` (:func:`smooth` twice,
    then the difference), the same float32 operations per pixel in one pass over the frame.

    ``image`` (H, W) of any real type is read as float32 (as ``astype``) and smoothed with the
    odd float32 ``inner`` weights; the second smoothing is a box of n taps of one float32 weight
    ``box``, whose every product ``box * a`` is formed once: the rows of ``a`` and of ``box * a``
    are kept in ``ring`` (2, n, W), a ring of the last n rows. Written to float32 ``out`` (H, W).
    ``pads`` (2, 1, W + 2 r) float32, r the larger radius, hold the first (along-columns) pass of
    a row of either smoothing with its ends repeated. The sums take three or four taps a pass
    over a row, and the helpers are inlined (``inline="always"``): the loop with one tap a pass,
    or with calls for every row, took 1.5-1.6 times as long on a 1024 x 1024 frame."""
    h, n = image.shape[0], ring.shape[1]
    big_r = n // 2
    taps = max(inner.size, n)
    rows, zero, shift = np.empty(taps, np.int64), np.zeros(taps, np.int64), np.arange(taps)
    done = 0  # rows of ``a`` made so far (row d in ring[:, d % n])
    for i in range(h):
        while done <= min(i + big_r, h - 1):
            values, scaled = ring[0, done % n], ring[1, done % n]
            _smooth_line(image, done, h, inner, rows, zero, shift, pads[0], values)
            for j in range(values.size):
                scaled[j] = values[j] * box
            done += 1
        for k in range(n):
            rows[k] = min(max(i - big_r + k, 0), h - 1) % n
        line, w = pads[1, 0], out.shape[1]
        _add_rows(ring[1], rows[:n], zero[:n], line[big_r: big_r + w])
        for j in range(big_r):
            line[j], line[big_r + w + j] = line[big_r], line[big_r + w - 1]
        for j in range(w + 2 * big_r):
            line[j] *= box
        _add_rows(pads[1], zero[:n], shift[:n], out[i])
        dst, centre = out[i], ring[0, i % n]
        for j in range(w):
            dst[j] = centre[j] - dst[j]
    return out


@njit(cache=True, error_model="numpy", inline="always")
def _add_rows(src, rows, shifts, out):
    """``out[j] = sum_k src[rows[k], shifts[k] + j]`` (float32), added from k = 0 and rounded at
    every step, three or four terms a pass over ``out``."""
    n, w = rows.size, out.size
    a = src[rows[0], shifts[0]: shifts[0] + w]
    if n < 4:
        for j in range(w):
            out[j] = a[j]
        k = 1
    else:
        b, c = src[rows[1], shifts[1]: shifts[1] + w], src[rows[2], shifts[2]: shifts[2] + w]
        d = src[rows[3], shifts[3]: shifts[3] + w]
        for j in range(w):
            out[j] = ((a[j] + b[j]) + c[j]) + d[j]
        k = 4
    while k + 3 <= n:
        a, b = src[rows[k], shifts[k]: shifts[k] + w], src[rows[k + 1], shifts[k + 1]: shifts[k + 1] + w]
        c = src[rows[k + 2], shifts[k + 2]: shifts[k + 2] + w]
        for j in range(w):
            out[j] = ((out[j] + a[j]) + b[j]) + c[j]
        k += 3
    for m in range(k, n):
        a = src[rows[m], shifts[m]: shifts[m] + w]
        for j in range(w):
            out[j] += a[j]
    return out


@njit(cache=True, error_model="numpy", inline="always")
def _smooth_line(src, i, h, weights, rows, zero, shift, pad, out):
    """Row ``i`` of :func:`smooth` of ``src`` (h, W) (any real type, read as float32) with
    ``weights`` into ``out`` (W,): the rows summed into ``pad`` (1, W + 2 r) beyond its ``r`` =
    len(weights) // 2 first values, its ends set to the row's end values (edges repeated), then
    ``pad`` summed along the row."""
    r, w = weights.size // 2, out.size
    for k in range(weights.size):
        rows[k] = min(max(i - r + k, 0), h - 1)
    line = pad[0]
    _tap_sum(src, rows, zero, weights, line[r: r + w])
    for j in range(r):
        line[j], line[r + w + j] = line[r], line[r + w - 1]
    _tap_sum(pad, zero, shift, weights, out)


@njit(cache=True, error_model="numpy", inline="always")
def _tap_sum(src, rows, shifts, weights, out):
    """``out[j] = sum_k weights[k] * src[rows[k], shifts[k] + j]`` (``src`` of any real type, read
    as float32), summed in float32 from k = 0 and rounded at every step (``out[j] += ...`` tap
    after tap: :func:`smooth`'s values), three or four taps a pass over ``out``."""
    n, w = weights.size, out.size
    a = src[rows[0], shifts[0]: shifts[0] + w]
    if n < 3:
        for j in range(w):
            out[j] = np.float32(a[j]) * weights[0]
        k = 1
    else:
        b, c = src[rows[1], shifts[1]: shifts[1] + w], src[rows[2], shifts[2]: shifts[2] + w]
        w0, w1, w2 = weights[0], weights[1], weights[2]
        for j in range(w):
            out[j] = (np.float32(a[j]) * w0 + w1 * np.float32(b[j])) + w2 * np.float32(c[j])
        k = 3
    while k + 4 <= n:
        a, b = src[rows[k], shifts[k]: shifts[k] + w], src[rows[k + 1], shifts[k + 1]: shifts[k + 1] + w]
        c, d = src[rows[k + 2], shifts[k + 2]: shifts[k + 2] + w], src[rows[k + 3], shifts[k + 3]: shifts[k + 3] + w]
        w0, w1, w2, w3 = weights[k], weights[k + 1], weights[k + 2], weights[k + 3]
        for j in range(w):
            out[j] = (((out[j] + w0 * np.float32(a[j])) + w1 * np.float32(b[j])) + w2 * np.float32(c[j])) + \
                w3 * np.float32(d[j])
        k += 4
    for m in range(k, n):
        a, w0 = src[rows[m], shifts[m]: shifts[m] + w], weights[m]
        for j in range(w):
            out[j] += w0 * np.float32(a[j])
    return out


@njit(cache=True, error_model="numpy")
def _clamped_sum(row, weights, j):
    """``sum_k weights[k] * row[j - r + k]`` with the index clamped to the row (edges repeated)."""
    w, r = row.size, weights.size // 2
    total = row[min(max(j - r, 0), w - 1)] * weights[0]
    for k in range(1, weights.size):
        total += weights[k] * row[min(max(j - r + k, 0), w - 1)]
    return total


@njit(cache=True, error_model="numpy")
def _along_x(grid, x0, x1, wx, clip):
    """The float32 ``grid`` (ny, nx) interpolated along x at every column: (ny, len(x0)),
    ``grid[:, x0] + wx * (grid[:, x1] - grid[:, x0])`` (float32 weights ``wx``, clipped to
    [0, 1] with ``clip``) -- the first half of :func:`.tile_geometry.grid_map`."""
    out = np.empty((grid.shape[0], x0.size), np.float32)
    for g in range(grid.shape[0]):
        for c in range(x0.size):
            weight = min(max(wx[c], np.float32(0.0)), np.float32(1.0)) if clip else wx[c]
            out[g, c] = grid[g, x0[c]] + weight * (grid[g, x1[c]] - grid[g, x0[c]])
    return out


@njit(cache=True, error_model="numpy")
def grid_map(grid, y0, y1, wy, x0, x1, wx):
    """The float32 ``grid`` interpolated bilinearly on the rows and columns given by ``y0, y1,
    wy`` (n_rows,) and ``x0, x1, wx`` (n_cols,) (float32 weights, used as they are): float32
    (n_rows, n_cols), as :func:`.tile_geometry.grid_map` did with numpy (along x first)."""
    along_x = _along_x(grid, x0, x1, wx, False)
    out = np.empty((y0.size, x0.size), np.float32)
    for i in range(y0.size):
        _along_y(along_x, y0[i], y1[i], wy[i], out[i])
    return out


@njit(cache=True, error_model="numpy")
def grid_at_points(grids, extrapolate, first, spacing, y, x):
    """The float64 ``grids`` (K, ny, nx), values at equally spaced centres (``first`` and
    ``spacing`` (2,): rows then columns), interpolated bilinearly at the N points (``y``, ``x``)
    (N,) float64: (K, N) float64, the upper grid value times the weight plus the lower one times
    one minus it, along x, then along y. Beyond the outer centres grid k is extended linearly
    (the weight clipped to [-0.75, 1.75], :func:`.tile_geometry.axis_weights`) where
    ``extrapolate[k]``, else held constant (the weight clipped to [0, 1])."""
    k_grids, ny, nx = grids.shape
    out = np.empty((k_grids, y.size))
    for p in range(y.size):
        y0, ty = _point_weight(y[p], first[0], spacing[0], ny)
        x0, tx = _point_weight(x[p], first[1], spacing[1], nx)
        y1, x1 = min(y0 + 1, ny - 1), min(x0 + 1, nx - 1)
        for k in range(k_grids):
            wy, wx = ty, tx
            if not extrapolate[k]:
                wy, wx = _clip(wy, 0.0, 1.0), _clip(wx, 0.0, 1.0)
            g = grids[k]
            top = g[y0, x0] * (1 - wx) + g[y0, x1] * wx
            bottom = g[y1, x0] * (1 - wx) + g[y1, x1] * wx
            out[k, p] = top * (1 - wy) + bottom * wy
    return out


@njit(cache=True, error_model="numpy")
def _point_weight(coord, first, spacing, n):
    """Lower centre index and upper weight (clipped to [-0.75, 1.75]) of ``coord`` between ``n``
    centres ``first + spacing * i`` (index 0 and weight 0 when ``n`` is 1; a NaN coordinate gets
    index 0 and a NaN weight, as numpy's clipped indices do)."""
    if n == 1:
        return 0, 0.0
    pos = (coord - first) / spacing
    if not pos >= 0.0:  # before the first centre, or NaN
        i0 = 0
    elif pos >= n - 2:
        i0 = n - 2
    else:
        i0 = int(np.floor(pos))
    return i0, _clip(pos - i0, -0.75, 1.75)


@njit(cache=True, error_model="numpy")
def _clip(value, low, high):
    """``value`` clipped to [low, high], NaN kept (as ``np.minimum(np.maximum(...))``)."""
    if value < low:
        return low
    return high if value > high else value


@njit(cache=True, error_model="numpy")
def gather_tiles(image, rows, cols, out):
    """The samples ``image[rows] x [cols]`` of an ny x nx grid of tiles into ``out`` (ny, nx, S)
    (of the image's type), tile by tile in raster order. ``rows`` (ny * nr,) and ``cols``
    (nx * nc,) hold each tile's rows and columns one tile after another."""
    ny, nx = out.shape[0], out.shape[1]
    nr, nc = rows.size // ny, cols.size // nx
    c0 = cols[0] if cols[-1] - cols[0] == cols.size - 1 else -1  # every column: no look-up
    for ty in range(ny):
        for tx in range(nx):  # tile by tile: the stack is written in order
            dst = out[ty, tx]
            for j in range(nr):
                if c0 >= 0:
                    src = image[rows[ty * nr + j], c0 + tx * nc: c0 + (tx + 1) * nc]
                    for i in range(nc):
                        dst[j * nc + i] = src[i]
                else:
                    for i in range(nc):
                        dst[j * nc + i] = image[rows[ty * nr + j], cols[tx * nc + i]]
    return out


@njit(cache=True, error_model="numpy")
def gather_residuals(image, rows, cols, grid, y0, y1, wy, x0, x1, wx, out, level_out):
    """As :func:`gather_tiles`, the samples less the level of the float32 ``grid`` interpolated
    bilinearly at each (``y0, y1, wy`` per entry of ``rows``, ``x0, x1, wx`` per entry of
    ``cols``, float32 weights; the order of :func:`.tile_geometry.grid_map`'s float32 arrays);
    that level is written to ``level_out`` (len(rows), len(cols)). Row by row of samples, with
    plain indices (slices of the rows in the inner loops took two thirds of its time)."""
    ny, nx = out.shape[0], out.shape[1]
    nr, nc = rows.size // ny, cols.size // nx
    along_x = _along_x(grid, x0, x1, wx, False)
    c0 = cols[0] if cols[-1] - cols[0] == cols.size - 1 else -1  # every column: no look-up
    for ty in range(ny):
        for j in range(nr):
            r = ty * nr + j
            lo, hi, weight, row = y0[r], y1[r], wy[r], rows[r]
            for c in range(cols.size):
                level_out[r, c] = (along_x[hi, c] - along_x[lo, c]) * weight + along_x[lo, c]
            for tx in range(nx):
                for i in range(nc):
                    c = tx * nc + i
                    value = image[row, c0 + c] if c0 >= 0 else image[row, cols[c]]
                    out[ty, tx, j * nc + i] = value - level_out[r, c]
    return out


@njit(cache=True, error_model="numpy")
def median3(padded):
    """3 x 3 median of every inner cell of ``padded`` (ny + 2, nx + 2): shape (ny, nx), the
    middle one of each neighbourhood's nine values (as ``scipy.ndimage.median_filter``), by a
    19-exchange selection network (Paeth's ``opt_med9``) on NaN-free values."""
    ny, nx = padded.shape[0] - 2, padded.shape[1] - 2
    out = np.empty((ny, nx), padded.dtype)
    for i in range(ny):
        for j in range(nx):
            p0, p1, p2 = padded[i, j], padded[i, j + 1], padded[i, j + 2]
            p3, p4, p5 = padded[i + 1, j], padded[i + 1, j + 1], padded[i + 1, j + 2]
            p6, p7, p8 = padded[i + 2, j], padded[i + 2, j + 1], padded[i + 2, j + 2]
            p1, p2 = min(p1, p2), max(p1, p2)
            p4, p5 = min(p4, p5), max(p4, p5)
            p7, p8 = min(p7, p8), max(p7, p8)
            p0, p1 = min(p0, p1), max(p0, p1)
            p3, p4 = min(p3, p4), max(p3, p4)
            p6, p7 = min(p6, p7), max(p6, p7)
            p1, p2 = min(p1, p2), max(p1, p2)
            p4, p5 = min(p4, p5), max(p4, p5)
            p7, p8 = min(p7, p8), max(p7, p8)
            p3 = max(p0, p3)
            p5 = min(p5, p8)
            p4, p7 = min(p4, p7), max(p4, p7)
            p6 = max(p3, p6)
            p4 = max(p1, p4)
            p2 = min(p2, p5)
            p4 = min(p4, p7)
            p4, p2 = min(p4, p2), max(p4, p2)
            p4 = max(p6, p4)
            out[i, j] = min(p4, p2)
    return out


@njit(cache=True, error_model="numpy")
def significance(image, level, noise, y0, y1, wy, x0, x1, wx, mode, out):
    """(image - level) / noise of float32 ``image`` (h, w), float32 (h, w). ``mode`` 0: ``level``
    and ``noise`` hold the constant level and the inverse of the constant noise (``[0, 0]``);
    1: ``level`` is the level at every pixel (h, w) and ``noise`` a grid; 2: both are grids. A
    grid is interpolated bilinearly (``y0, y1, wy`` per row, ``x0, x1, wx`` per column, float32;
    the noise's weights clipped to [0, 1], the level's as given), in the order of
    :func:`.tile_geometry.grid_map`'s float32 arrays. Written to float32 ``out`` (h, w)."""
    h, w = image.shape
    if mode == 0:
        for i in range(h):
            for j in range(w):
                out[i, j] = (image[i, j] - level[0, 0]) * noise[0, 0]
        return out
    noise_x = _along_x(noise, x0, x1, wx, True)
    level_x = _along_x(level, x0, x1, wx, False) if mode == 2 else noise_x
    sd, lvl = np.empty(w, np.float32), np.empty(w, np.float32)
    zero, one = np.float32(0.0), np.float32(1.0)
    for i in range(h):
        _along_y(noise_x, y0[i], y1[i], min(max(wy[i], zero), one), sd)
        if mode == 2:
            _along_y(level_x, y0[i], y1[i], wy[i], lvl)
        _divide_row(image[i], lvl if mode == 2 else level[i], sd, out[i])
    return out


@njit(cache=True, error_model="numpy")
def _along_y(rows, y0, y1, weight, out):
    """Row ``out`` (n,) = ``low + (high - low) * weight`` between rows ``y0`` and ``y1`` of the
    :func:`_along_x` grid ``rows`` -- the second half of :func:`.tile_geometry.grid_map`."""
    low, high = rows[y0], rows[y1]
    for c in range(out.size):
        out[c] = (high[c] - low[c]) * weight + low[c]


@njit(cache=True, error_model="numpy")
def _divide_row(row, level, noise, out):
    """out = (row - level) / noise, element by element (float32 rows of one length)."""
    for j in range(out.size):
        out[j] = (row[j] - level[j]) / noise[j]


@njit(cache=True, error_model="numpy")
def _root(parent, a):
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@njit(cache=True, error_model="numpy")
def _union(parent, a, b):
    """Join the sets of a and b under the smaller root (the earlier label in raster order)."""
    a, b = _root(parent, a), _root(parent, b)
    if a < b:
        parent[b] = a
    elif b < a:
        parent[a] = b


@njit(cache=True, error_model="numpy")
def _provisional(flat, w):
    """Raster scan of the True pixels (flat indices ``flat``, increasing, of an image ``w`` wide):
    the provisional label of each, and the union-find parents of the labels (8-connected to the
    row above and the pixel before). Two rows of labels, stamped with their row, stand for the
    mask's rows, so that only the True pixels are visited."""
    label = np.empty(flat.size, np.int64)
    parent = np.empty(max(flat.size, 1), np.int64)
    row_label = np.empty((2, w), np.int64)
    stamp = np.full((2, w), -2, np.int64)
    n = 0
    for m in range(flat.size):
        i, j = flat[m] // w, flat[m] % w
        here, above = i & 1, (i - 1) & 1
        mine = row_label[here, j - 1] if j > 0 and stamp[here, j - 1] == i else -1
        for jj in range(max(j - 1, 0), min(j + 2, w)):
            if stamp[above, jj] == i - 1:
                if mine < 0:
                    mine = row_label[above, jj]
                else:
                    _union(parent, mine, row_label[above, jj])
        if mine < 0:
            parent[n] = mine = n
            n += 1
        label[m], row_label[here, j], stamp[here, j] = mine, mine, i
    return label, parent[:n]


@njit(cache=True, error_model="numpy")
def label8(flat, w):
    """8-connected regions of the True pixels of a mask ``w`` pixels wide, given by their flat
    indices ``flat`` (increasing), numbered in raster order of their first pixels
    (``scipy.ndimage.label``'s order), each region's pixels in raster order. Returns (index, y,
    x) of shape (M,) grouped region after region, and starts (N,), int64."""
    label, parent = _provisional(flat, w)
    final = np.empty(parent.size, np.int64)
    n = 0
    for a in range(parent.size):  # a root precedes the labels joined to it
        root = _root(parent, a)
        if root == a:
            final[a] = n
            n += 1
        else:
            final[a] = final[root]
    counts = np.zeros(n, np.int64)
    for k in range(flat.size):
        counts[final[label[k]]] += 1
    starts = np.empty(n, np.int64)
    total = 0
    for r in range(n):
        starts[r] = total
        total += counts[r]
    fill = starts.copy()
    index, y, x = np.empty(flat.size, np.int64), np.empty(flat.size, np.int64), np.empty(flat.size, np.int64)
    for k in range(flat.size):
        r = final[label[k]]
        p = fill[r]
        fill[r] += 1
        index[p], y[p], x[p] = r, flat[k] // w, flat[k] % w
    return index, y, x, starts


@njit(cache=True, error_model="numpy")
def separable_moments(q, wx, dx, wy, dy):
    """``M[k, n, a, b] = sum_j wy[n, j] dy[n, j]^a sum_i q[k, n, j, i] wx[n, i] dx[n, i]^b`` for
    float64 ``q`` (K, N, S, S) and (N, S) axis weights and coordinates, a, b in 0, 1, 2: the sum
    over i first, then over j (the order of :func:`.windows.separable_moments`'s two matrix
    products). Returns (K, N, 3, 3) float64."""
    n_stacks, n, s = q.shape[0], q.shape[1], q.shape[2]
    out = np.zeros((n_stacks, n, 3, 3))
    along = np.empty((s, 3))
    for w in range(n):
        for k in range(n_stacks):
            for j in range(s):
                m0 = m1 = m2 = 0.0
                for i in range(s):
                    v = q[k, w, j, i] * wx[w, i]
                    m0 += v
                    m1 += v * dx[w, i]
                    m2 += v * dx[w, i] * dx[w, i]
                along[j, 0], along[j, 1], along[j, 2] = m0, m1, m2
            for j in range(s):
                y0 = wy[w, j]
                y1 = y0 * dy[w, j]
                y2 = y1 * dy[w, j]
                for b in range(3):
                    out[k, w, 0, b] += y0 * along[j, b]
                    out[k, w, 1, b] += y1 * along[j, b]
                    out[k, w, 2, b] += y2 * along[j, b]
    return out


@njit(cache=True, error_model="numpy")
def extract_windows(data, cx, cy, half, invalid):
    """(2 half + 1)-pixel windows of ``data`` (H, W) centred on pixels (cx, cy) (N,) as float64
    (N, S, S), ``values[n, j, i]`` = pixel (cx - half + i, cy - half + j); NaN beyond the border
    and where bool ``invalid`` (H, W) is True (``invalid`` may be empty: none)."""
    h, w = data.shape
    size = 2 * half + 1
    check = invalid.size > 0
    out = np.empty((cx.size, size, size))
    for n in range(cx.size):
        for j in range(size):
            y = cy[n] - half + j
            for i in range(size):
                x = cx[n] - half + i
                if 0 <= y < h and 0 <= x < w and not (check and invalid[y, x]):
                    out[n, j, i] = data[y, x]
                else:
                    out[n, j, i] = np.nan
    return out
