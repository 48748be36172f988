"""The compiled loops of the streak path (numba): the blurred-arc model of one streak and its
Levenberg-Marquardt fit to the pixels of a window, and the line filter of the segmentation.

Kept apart so that importing startrack does not import numba; :mod:`._streak_fit` and
:mod:`._streak_find` load this module on first use. Compiled functions are cached on disk
(``cache=True``); every array is float64 (labels int32) and C-contiguous.

The model (:func:`arc_pixel`) is the image of a star moving at a uniform pace along a parabolic
arc for the whole exposure, blurred by a Gaussian of sigma ``s``: with the chord from
``c - h`` to ``c + h`` (half-length ``H = |h|``, unit ``u = h / H``, normal ``n``), a pixel at
``q = (x, y) - c`` has ``t = q . u`` along and ``d = q . n - sag (1 - t^2 / H^2)`` across the arc,
and

    I = b + a (1 + g t / H) exp(-d^2 / 2 s^2) [erf((t + H) / sqrt(2) s) - erf((t - H) / sqrt(2) s)] / 2

Parameters ``p`` = (cx, cy, hx, hy, sag, a, g, b, s) (:data:`NPAR`): the arc's ends are
``c -+ h`` exactly, ``sag`` is the arc's offset from the chord at its middle (px), ``g`` a linear
change of brightness along it (a non-uniform pace: angular acceleration, or the projection), ``b``
the local background. Pixel integration is not modelled: a box pixel adds 1/12 px^2 to the blur's
variance in every direction, which ``s`` absorbs.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

NPAR = 9
CX, CY, HX, HY, SAG, AMP, GRAD, BG, SIG = range(NPAR)
SQRT2 = math.sqrt(2.0)
SQRTPI = math.sqrt(math.pi)
SIGMA_BOUNDS = (0.3, 6.0)
"""The blur is kept in this range (px) during a fit."""

FIT_OK, FIT_NOT_CONVERGED, FIT_TOO_FEW_PIXELS, FIT_SINGULAR = 0, 1, 2, 3
"""Flags of :func:`fit_arcs`."""


NGEO = 12
"""Derived constants of one arc (:func:`geometry`): cx, cy, ux, uy, H, 1/H, sag, a, g, b, s, 1/s."""


@njit(cache=True)
def geometry(p, geo):
    """Fill ``geo`` (:data:`NGEO`,) with the per-arc constants of parameters ``p`` (9,)."""
    half = math.sqrt(p[HX] * p[HX] + p[HY] * p[HY])
    geo[0], geo[1] = p[CX], p[CY]
    geo[2], geo[3] = p[HX] / half, p[HY] / half
    geo[4], geo[5] = half, 1.0 / half
    geo[6], geo[7], geo[8], geo[9] = p[SAG], p[AMP], p[GRAD], p[BG]
    geo[10], geo[11] = p[SIG], 1.0 / p[SIG]


ERF_P = 0.3275911
ERF_A = (0.254829592, -0.284496736, 1.421413741, -1.453152027, 1.061405429)
"""Abramowitz & Stegun (1964) 7.1.26: erf(z) = 1 - t (a1 + a2 t + ... + a5 t^4) exp(-z^2) with
t = 1 / (1 + p z), z >= 0, to within 1.5e-7: the model's along factor at a fifth of math.erf's
cost, since its derivatives need exp(-z^2) anyway."""


@njit(cache=True, fastmath=True, inline="always")
def erf_given_exp(z, exp_minus_z2):
    """erf(z) from ``exp(-z^2)`` (A&S 7.1.26, :data:`ERF_A`; absolute error under 1.5e-7)."""
    a1, a2, a3, a4, a5 = ERF_A
    t = 1.0 / (1.0 + ERF_P * abs(z))
    value = 1.0 - t * (a1 + t * (a2 + t * (a3 + t * (a4 + t * a5)))) * exp_minus_z2
    return value if z >= 0.0 else -value


@njit(cache=True, fastmath=True)
def arc_value(x, y, geo):
    """The model at pixel (x, y) from the arc's constants ``geo`` (no derivatives)."""
    ux, uy, half, inv_half, inv_s = geo[2], geo[3], geo[4], geo[5], geo[11]
    qx, qy = x - geo[0], y - geo[1]
    t = qx * ux + qy * uy
    d = -qx * uy + qy * ux - geo[6] * (1.0 - (t * inv_half) ** 2)
    zs = d * inv_s
    along = 1.0
    k = inv_s / SQRT2
    zp, zm = (t + half) * k, (t - half) * k
    if not (zp > 4.5 and zm < -4.5):
        along = 0.5 * (erf_given_exp(zp, math.exp(-zp * zp)) - erf_given_exp(zm, math.exp(-zm * zm)))
    return geo[9] + geo[7] * (1.0 + geo[8] * t * inv_half) * math.exp(-0.5 * zs * zs) * along


@njit(cache=True, fastmath=True)
def arc_jacobian(x, y, geo, jac):
    """The model at pixel (x, y) from the arc's constants ``geo``; fills ``jac`` (9,) with dI/dp."""
    ux, uy, half, inv_half = geo[2], geo[3], geo[4], geo[5]
    sag, amp, grad, inv_s = geo[6], geo[7], geo[8], geo[11]
    nx, ny = -uy, ux
    qx, qy = x - geo[0], y - geo[1]
    t = qx * ux + qy * uy
    d0 = qx * nx + qy * ny
    tr = t * inv_half
    w = 1.0 - tr * tr
    d = d0 - sag * w
    zs = d * inv_s
    across = math.exp(-0.5 * zs * zs)
    lin = 1.0 + grad * tr
    amp_t = amp * lin
    k = inv_s / SQRT2
    zp, zm = (t + half) * k, (t - half) * k
    if zp > 4.5 and zm < -4.5:  # inside the arc, away from its ends: the along factor is 1 to 1e-9
        along, e_t, e_h, e_s = 1.0, 0.0, 0.0, 0.0
    else:
        ep, em = math.exp(-zp * zp), math.exp(-zm * zm)
        along = 0.5 * (erf_given_exp(zp, ep) - erf_given_exp(zm, em))
        c = k / SQRTPI
        e_t, e_h, e_s = c * (ep - em), c * (ep + em), (zp * ep - zm * em) * inv_s / SQRTPI
    core = across * along
    di_dd = -amp_t * core * zs * inv_s
    di_dt = amp * grad * inv_half * core + di_dd * (2.0 * sag * tr * inv_half) + amp_t * across * e_t
    di_dh = -amp * grad * tr * inv_half * core - di_dd * (2.0 * sag * tr * tr * inv_half) + amp_t * across * e_h
    cross = (di_dt * d0 - di_dd * t) * inv_half
    jac[CX] = -di_dt * ux - di_dd * nx
    jac[CY] = -di_dt * uy - di_dd * ny
    jac[HX] = cross * nx + di_dh * ux
    jac[HY] = cross * ny + di_dh * uy
    jac[SAG] = -di_dd * w
    jac[AMP] = lin * core
    jac[GRAD] = amp * tr * core
    jac[BG] = 1.0
    jac[SIG] = amp_t * (core * zs * zs * inv_s - across * e_s)
    return geo[9] + amp_t * core


@njit(cache=True)
def arc_pixel(x, y, p, jac):
    """The model at pixel (x, y) of parameters ``p`` (module docstring); fills ``jac`` (9,) with
    dI/dp; returns I."""
    geo = np.empty(NGEO)
    geometry(p, geo)
    return arc_jacobian(x, y, geo, jac)


@njit(cache=True)
def _inside(x, y, p, reach, band):
    """Whether pixel (x, y) is near the arc of ``p``: within ``reach`` px beyond its ends and
    ``band`` px across it."""
    cx, cy, hx, hy, sag = p[0], p[1], p[2], p[3], p[4]
    half = math.sqrt(hx * hx + hy * hy)
    ux, uy = hx / half, hy / half
    t = (x - cx) * ux + (y - cy) * uy
    if abs(t) > half + reach:
        return False
    tc = min(abs(t), half)
    d = -(x - cx) * uy + (y - cy) * ux - sag * (1.0 - (tc / half) ** 2)
    return abs(d) <= band


@njit(cache=True)
def _row_span(dy, ux, uy, across, t_lo, t_hi):
    """The x offsets (lo, hi) from a line's point c, on the row ``dy`` px from it, of the pixels
    within ``across`` px of the line (direction (ux, uy), unit) and between ``t_lo`` and ``t_hi``
    px from c along it: the two slabs' intersection (lo > hi when the row misses it)."""
    lo, hi = -math.inf, math.inf
    if abs(uy) > 1e-12:  # |-x uy + dy ux| <= across
        a, b = (dy * ux - across) / uy, (dy * ux + across) / uy
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    elif abs(dy * ux) > across:
        return 1.0, -1.0
    if abs(ux) > 1e-12:  # t_lo <= x ux + dy uy <= t_hi
        a, b = (t_lo - dy * uy) / ux, (t_hi - dy * uy) / ux
        lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
    elif not t_lo <= dy * uy <= t_hi:
        return 1.0, -1.0
    return lo, hi


@njit(cache=True)
def gather(image, labels, bin_px, own, p, reach, band, saturation, checkerboard, xs, ys, vs):
    """Pixels of ``image`` (H, W) near the arc ``p`` into ``xs, ys, vs`` (their capacity bounds
    the count); returns the count. A pixel whose label (``labels`` on a grid ``bin_px`` times
    coarser; 0 = none) is another streak's, or at or above ``saturation``, is left out; with
    ``checkerboard``, so is every other pixel (a first pass at half the cost)."""
    height, width = image.shape
    cx, cy, hx, hy = p[0], p[1], p[2], p[3]
    half = math.sqrt(hx * hx + hy * hy)
    extent = half + reach + abs(p[4]) + band
    x0, x1 = max(int(math.floor(cx - extent)), 0), min(int(math.ceil(cx + extent)), width - 1)
    y0, y1 = max(int(math.floor(cy - extent)), 0), min(int(math.ceil(cy + extent)), height - 1)
    count, capacity = 0, xs.shape[0]
    lh, lw = labels.shape
    ux, uy = hx / half, hy / half
    across, along = band + abs(p[4]) + 1.0, half + reach + 1.0  # slabs that hold every pixel _inside accepts
    for y in range(y0, y1 + 1):
        lo, hi = _row_span(y - cy, ux, uy, across, -along, along)
        for x in range(max(x0, int(math.floor(cx + lo))), min(x1, int(math.ceil(cx + hi))) + 1):
            if count >= capacity:
                return count
            if checkerboard and (x + y) % 2 == 1:
                continue
            value = image[y, x]
            if value >= saturation or not _inside(x, y, p, reach, band):
                continue
            ly, lx = y // bin_px, x // bin_px
            if ly < lh and lx < lw:
                lab = labels[ly, lx]
                if lab != 0 and lab != own:
                    continue
            xs[count], ys[count], vs[count] = x, y, value
            count += 1
    return count


@njit(cache=True, fastmath=True)
def _system(p, xs, ys, vs, wts, n, jtj, jtr, jac):
    """chi^2 of ``p`` over the n pixels (weights 1 / sigma^2), and J^T W J, J^T W r into jtj, jtr."""
    geo = np.empty(NGEO)
    geometry(p, geo)
    jtj[:, :] = 0.0
    jtr[:] = 0.0
    chi2 = 0.0
    for i in range(n):
        r = vs[i] - arc_jacobian(xs[i], ys[i], geo, jac)
        w = wts[i]
        chi2 += w * r * r
        for a in range(NPAR):
            wa = w * jac[a]
            jtr[a] += wa * r
            for b in range(a, NPAR):
                jtj[a, b] += wa * jac[b]
    for a in range(NPAR):
        for b in range(a):
            jtj[a, b] = jtj[b, a]
    return chi2


@njit(cache=True)
def _clamped(p):
    """Keep the blur in :data:`SIGMA_BOUNDS`, the amplitude non-negative, the arc at least 0.5 px long."""
    p[SIG] = min(max(p[SIG], SIGMA_BOUNDS[0]), SIGMA_BOUNDS[1])
    p[AMP] = max(p[AMP], 0.0)
    p[GRAD] = min(max(p[GRAD], -0.9), 0.9)
    half = math.sqrt(p[HX] ** 2 + p[HY] ** 2)
    if half < 0.25:
        p[HX], p[HY] = p[HX] / max(half, 1e-9) * 0.25, p[HY] / max(half, 1e-9) * 0.25


@njit(cache=True)
def _weights(p, xs, ys, n, var_bg, shot, wts):
    """Weights 1 / (var_bg + shot * max(model - b, 0)) of the n pixels, the model taken at ``p``."""
    geo = np.empty(NGEO)
    geometry(p, geo)
    for i in range(n):
        signal = arc_value(xs[i], ys[i], geo) - p[BG]
        wts[i] = 1.0 / (var_bg + shot * max(signal, 0.0))


@njit(cache=True)
def _small_step(step, jtj, fraction):
    """Whether ``step`` (9,) moves each end (in x and in y), the sag and the blur by less than
    ``fraction`` of its 1-sigma, the sigmas from the inverse of ``jtj`` (9, 9)."""
    try:
        inv = np.linalg.inv(jtj)
    except Exception:  # noqa: BLE001 - numba raises a generic error on a singular system
        return False
    for a, b in ((CX, HX), (CY, HY)):  # an end moves by |dc| + |dh| at most; var(end) ~ var(c) + var(h)
        if not (abs(step[a]) + abs(step[b])) ** 2 <= fraction * fraction * (inv[a, a] + inv[b, b]):
            return False
    for a in (SAG, SIG):
        if not step[a] * step[a] <= fraction * fraction * inv[a, a]:
            return False
    return True


@njit(cache=True)
def levenberg_marquardt(p, xs, ys, vs, wts, n, max_iter, tol_px, step_sigmas, cov):
    """Fit ``p`` (9,) in place to n pixels; ``cov`` (9, 9) gets (J^T W J)^-1 at the end.

    Returns (chi^2, iterations, flag) with flag :data:`FIT_OK`, :data:`FIT_NOT_CONVERGED` or
    :data:`FIT_SINGULAR`. Converged: a step moves no end, the sag or the blur by more than
    ``tol_px``, or moves each of them by less than ``step_sigmas`` of its own 1-sigma
    (:func:`_small_step`: a faint streak's ends are known to a pixel or so, and chasing them to
    ``tol_px`` took most of the iterations)."""
    jtj, trial_jtj = np.zeros((NPAR, NPAR)), np.zeros((NPAR, NPAR))
    jtr, trial_jtr = np.zeros(NPAR), np.zeros(NPAR)
    jac = np.zeros(NPAR)
    trial = np.zeros(NPAR)
    lam = 1e-3
    chi2 = _system(p, xs, ys, vs, wts, n, jtj, jtr, jac)
    flag = FIT_NOT_CONVERGED
    iterations = 0
    while iterations < max_iter:
        iterations += 1
        damped = jtj.copy()
        for a in range(NPAR):
            damped[a, a] += lam * max(jtj[a, a], 1e-12)
        try:
            step = np.linalg.solve(damped, jtr)
        except Exception:  # noqa: BLE001 - numba raises a generic error on a singular system
            flag = FIT_SINGULAR
            break
        trial[:] = p + step
        _clamped(trial)
        # the trial's normal equations at once: most steps are taken, and a separate chi^2 pass before
        # them made the fits of 40 streak-mode frames 14 % slower (docs/attitude_and_rate.md)
        new = _system(trial, xs, ys, vs, wts, n, trial_jtj, trial_jtr, jac)
        if new <= chi2:
            moved = max(abs(step[CX]) + abs(step[HX]), abs(step[CY]) + abs(step[HY]))
            moved = max(moved, max(abs(step[SAG]), abs(step[SIG])))
            p[:] = trial
            jtj[:, :] = trial_jtj
            jtr[:] = trial_jtr
            chi2 = new
            lam = max(lam / 3.0, 1e-9)
            if moved < tol_px or _small_step(step, jtj, step_sigmas):
                flag = FIT_OK
                break
        else:
            lam *= 4.0
            if lam > 1e8:
                flag = FIT_OK if chi2 > 0 else FIT_NOT_CONVERGED  # no step improves: at the minimum
                break
    try:
        cov[:, :] = np.linalg.inv(jtj)
    except Exception:  # noqa: BLE001
        flag = FIT_SINGULAR
    return chi2, iterations, flag


@njit(cache=True)
def fit_arcs(image, labels, bin_px, own, start, reach, band, saturation, var_bg, shot, checkerboard, max_iter,
             tol_px, step_sigmas, max_windows, capacity, params, covs, stats):
    """Fit K arcs to ``image`` (H, W): ``start`` (K, 9) the first guesses, ``own`` (K,) each one's
    label (0: none), ``reach`` and ``band`` (K,) the window around each first guess (px beyond the
    ends, px across). Results into ``params`` (K, 9), ``covs`` (K, 9, 9) and ``stats`` (K, 4):
    chi^2, pixels used, iterations, flag.

    Each pixel is weighted by 1 / (``var_bg`` + ``shot`` x signal), the signal being the first
    guess's model above its background and ``shot`` the variance per unit of signal (1 / gain in
    image units; 0: background noise only), so that a bright streak's photon noise is in its
    covariance; ``checkerboard`` fits every other pixel only (:func:`gather`). ``max_iter``,
    ``tol_px`` and ``step_sigmas`` are :func:`levenberg_marquardt`'s. An arc whose end moves
    more than half of ``reach`` from the window's is fitted again in a window around its new
    ends (at most ``max_windows`` windows), so that a first guess too short finds the ends."""
    xs, ys, vs, wts = np.empty(capacity), np.empty(capacity), np.empty(capacity), np.empty(capacity)
    cov = np.zeros((NPAR, NPAR))
    for k in range(start.shape[0]):
        p = start[k].copy()
        window = p.copy()
        iterations, chi2, flag, n = 0, 0.0, FIT_TOO_FEW_PIXELS, 0
        for _ in range(max_windows):
            n = gather(image, labels, bin_px, own[k], window, reach[k], band[k], saturation, checkerboard, xs, ys, vs)
            if n < 4 * NPAR:
                flag = FIT_TOO_FEW_PIXELS
                break
            _weights(window, xs, ys, n, var_bg, shot, wts)
            chi2, more, flag = levenberg_marquardt(p, xs, ys, vs, wts, n, max_iter, tol_px, step_sigmas, cov)
            iterations += more
            if flag == FIT_SINGULAR or _end_shift(p, window) < 0.5 * reach[k]:
                break
            window[:] = p  # an end walked to the window's edge: gather again around the new arc
        stats[k, 1] = n
        params[k] = p
        covs[k] = cov
        stats[k, 0], stats[k, 2], stats[k, 3] = chi2, iterations, flag


@njit(cache=True)
def _end_shift(p, window):
    """Largest distance (px) of the arc's ends from those of the window it was gathered for."""
    worst = 0.0
    for sign in (-1.0, 1.0):
        dx = (p[CX] + sign * p[HX]) - (window[CX] + sign * window[HX])
        dy = (p[CY] + sign * p[HY]) - (window[CY] + sign * window[HY])
        worst = max(worst, math.sqrt(dx * dx + dy * dy))
    return worst


@njit(cache=True)
def shot_sums(image, labels, bin_px, own, fitted, reach, band, saturation, var_bg, capacity):
    """(sum s (r^2 - var_bg), sum s^2) over the pixels of K fitted arcs (K, 9), s the model's
    signal above its background and r the residual: their ratio estimates the photon-noise
    variance per unit of signal (1 / gain)."""
    xs, ys, vs = np.empty(capacity), np.empty(capacity), np.empty(capacity)
    geo = np.empty(NGEO)
    num, den = 0.0, 0.0
    for k in range(fitted.shape[0]):
        p = fitted[k].copy()
        n = gather(image, labels, bin_px, own[k], p, reach[k], band[k], saturation, False, xs, ys, vs)
        geometry(p, geo)
        for i in range(n):
            model = arc_value(xs[i], ys[i], geo)
            signal = model - p[BG]
            if signal > 0.0:
                r = vs[i] - model
                num += signal * (r * r - var_bg)
                den += signal * signal
    return num, den


@njit(cache=True)
def profile_runs(image, cx, cy, ux, uy, t_lo, t_hi, band, background, smooth, min_run, runs):
    """The pieces of a line where a streak lies: the mean signal per pixel of length along the
    line through (cx, cy) with direction (ux, uy) (unit), over [t_lo, t_hi] px and ``band`` px
    across it, smoothed over ``smooth`` px; its runs above half the plateau (the 75th percentile
    of the smoothed profile) at least ``min_run`` px long (gaps under 3 px closed) go into
    ``runs`` (M, 3) as (t_start, t_end, plateau); returns their number (at most M)."""
    height, width = image.shape
    n = int(t_hi - t_lo) + 1
    total, count = np.zeros(n), np.zeros(n)
    extent = max(abs(t_lo), abs(t_hi)) + band + 1.0
    x0, x1 = max(int(cx - extent), 0), min(int(cx + extent) + 1, width - 1)
    y0, y1 = max(int(cy - extent), 0), min(int(cy + extent) + 1, height - 1)
    for y in range(y0, y1 + 1):
        lo, hi = _row_span(y - cy, ux, uy, band + 1.0, t_lo - 1.0, t_hi + 1.0)
        for x in range(max(x0, int(math.floor(cx + lo))), min(x1, int(math.ceil(cx + hi))) + 1):
            t = (x - cx) * ux + (y - cy) * uy
            d = -(x - cx) * uy + (y - cy) * ux
            if abs(d) > band or t < t_lo or t > t_hi:
                continue
            k = int(t - t_lo + 0.5)
            if 0 <= k < n:
                total[k] += image[y, x] - background
                count[k] += 1.0
    density = np.zeros(n)
    for k in range(n):
        if count[k] > 0:
            density[k] = total[k] / count[k] * (2.0 * band + 1.0)
    half = smooth // 2
    level = np.zeros(n)
    for k in range(n):
        lo, hi = max(k - half, 0), min(k + half + 1, n)
        level[k] = density[lo:hi].mean()
    plateau = np.sort(level)[min(int(0.75 * n), n - 1)]
    found = 0
    k = 0
    while k < n and found < runs.shape[0]:
        if level[k] < 0.5 * plateau:
            k += 1
            continue
        first = k
        last = k
        gap = 0
        while k < n and gap < max(3, half):
            if level[k] >= 0.5 * plateau:
                last = k
                gap = 0
            else:
                gap += 1
            k += 1
        if last - first + 1 >= min_run:
            runs[found, 0], runs[found, 1], runs[found, 2] = t_lo + first - 0.5, t_lo + last + 0.5, plateau
            found += 1
    return found


@njit(cache=True)
def line_filter(image, length, orientations, out):
    """Largest mean of ``image`` (H, W) over ``length`` pixels along a line through each pixel,
    over ``orientations`` directions in [0, pi), into ``out`` (H, W) (taps at the nearest pixel;
    pixels outside the image count as 0). The image is padded with zeros and each tap is added
    to a running sum in a contiguous sweep of the rows, which the compiler vectorises; the sums
    are the same, in the same order, as tap after tap at each pixel."""
    height, width = image.shape
    half = (length - 1) // 2
    padded = np.zeros((height + 2 * half, width + 2 * half))
    padded[half:half + height, half:half + width] = image
    total = np.empty((height, width))
    for y in range(height):
        for x in range(width):
            out[y, x] = -np.inf
    offsets = np.empty((length, 2), dtype=np.int64)
    for k in range(orientations):
        angle = math.pi * k / orientations
        ca, sa = math.cos(angle), math.sin(angle)
        for j in range(length):
            offsets[j, 0] = int(round((j - half) * ca)) + half
            offsets[j, 1] = int(round((j - half) * sa)) + half
        total[:, :] = 0.0
        for j in range(length):  # tap by tap, each a contiguous sweep of the rows
            dx, dy = offsets[j, 0], offsets[j, 1]
            for y in range(height):
                row = padded[y + dy]
                for x in range(width):
                    total[y, x] += row[x + dx]
        for y in range(height):
            for x in range(width):
                mean = total[y, x] / length
                if mean > out[y, x]:
                    out[y, x] = mean


@njit(cache=True)
def block_sums(image, bin_px, out):
    """Sums of ``image`` (H, W) over ``bin_px`` x ``bin_px`` blocks into ``out``
    (H // bin_px, W // bin_px), in one pass (trailing rows and columns are left out)."""
    rows, cols = out.shape
    for i in range(rows):
        for j in range(cols):
            out[i, j] = 0.0
    for y in range(rows * bin_px):
        i = y // bin_px
        for j in range(cols):
            total = 0.0
            for x in range(j * bin_px, (j + 1) * bin_px):
                total += image[y, x]
            out[i, j] += total


@njit(cache=True, fastmath=True)
def rodrigues(vectors, theta, out):
    """``exp(-[theta x]) v`` (Rodrigues) of vectors (N, 3) by rotation vectors theta (N, 3)
    (rad), row by row, into ``out`` (N, 3): the rotations of the joint fit's predictions
    (:func:`._streak_model.rotate`), without numpy's temporaries."""
    for i in range(vectors.shape[0]):
        tx, ty, tz = theta[i, 0], theta[i, 1], theta[i, 2]
        vx, vy, vz = vectors[i, 0], vectors[i, 1], vectors[i, 2]
        angle = math.sqrt(tx * tx + ty * ty + tz * tz)
        if angle == 0.0:
            out[i, 0], out[i, 1], out[i, 2] = vx, vy, vz
            continue
        kx, ky, kz = -tx / angle, -ty / angle, -tz / angle
        cos, sin = math.cos(angle), math.sin(angle)
        dot = (kx * vx + ky * vy + kz * vz) * (1.0 - cos)
        out[i, 0] = vx * cos + (ky * vz - kz * vy) * sin + kx * dot
        out[i, 1] = vy * cos + (kz * vx - kx * vz) * sin + ky * dot
        out[i, 2] = vz * cos + (kx * vy - ky * vx) * sin + kz * dot
