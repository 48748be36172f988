"""Fit the blurred-arc model of :mod:`._streak_kernel` to the pixels around each streak of a frame.

Each streak is fitted alone, in a window around its first guess: the moments of a candidate blob
(:mod:`._streak_find`, lost-in-space) or the arc predicted from an attitude and a rate (tracking,
:mod:`._streak_track`). Two passes (:func:`fit_streaks`): the first in a wide window around the
first guess, weighted by the background noise only; the second in a tight window around the
first result (so that a curved streak is followed), with each pixel weighted by the background
variance plus its photon noise, ``shot`` times the model's signal. ``shot`` (1 / gain, image
units) is estimated from the first pass's residuals when not given. Pixels at the ADC's maximum
(a saturated streak's core) are left out: clipped pixels pulled the fitted ends outward on the
brightest streaks (``docs/attitude_and_rate.md``).

A fit's six geometric numbers are turned into the measurement the attitude-and-rate fit
(:mod:`._streak_model`) uses, with its covariance: the two ends ``c -+ h`` (px) and the light
centroid ``c + (g H / 3) u + (2 sag / 3) n`` (the mean of the model's light: the star's mean
position over the exposure), the covariance being the fit's (J^T W J)^-1 scaled by its reduced
chi-square when that exceeds 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError
from ._streak_find import StreakCandidates, kernel

NPAR = 9
CAPACITY = 200_000
"""Most pixels one window may hold."""
MAX_ITER = 25
TOL_PX = 0.01
FIRST_TOL_PX = 0.05
FIRST_STEP_SIGMAS = 0.5
"""The first pass stops at a step of this size, or this many of each end's, the sag's and the
blur's 1-sigma: the second, on every pixel of a tight window, refines it."""
STEP_SIGMAS = 0.2
"""The second pass stops at a step of ``TOL_PX`` or this many 1-sigma (:mod:`._streak_kernel`)."""
MAX_WINDOWS = 3
"""Windows one fit may move through (:func:`._streak_kernel.fit_arcs`)."""
BLUR_RANGE_PX = (0.45, 4.5)
"""A fitted blur outside this range is not one star's streak."""
MIN_FLUX_SNR = 8.0
MAX_END_SIGMA_PX = 2.0
EDGE_MARGIN_SIGMAS = 3.0
"""An end nearer than this many blurs to the image border may be cut by it."""
MIN_LENGTH_PX = 3.0
SATURATION_BITS = (8, 10, 12, 14, 16)
"""An integer frame whose largest value is 2^bits - 1 for one of these is saturated there."""


@dataclass(frozen=True)
class StreakFits:
    """The fitted arcs of K streaks (rows in the order of the first guesses).

    Attributes
    ----------
    params : ndarray, shape (K, 9)
        (cx, cy, hx, hy, sag, a, g, b, s) of :mod:`._streak_kernel` (px, image units).
    cov : ndarray, shape (K, 9, 9)
        Their covariance, scaled up by the reduced chi-square when it exceeds 1.
    chi2_red : ndarray, shape (K,)
        Chi-square per degree of freedom (with the photon noise in the weights).
    n_pixels : ndarray of int, shape (K,)
    ok : ndarray of bool, shape (K,)
        A clean streak (``reasons`` says why not).
    reasons : tuple of str
    label : ndarray of int32, shape (K,)
        The candidate blob of each first guess (0 for a predicted one).
    shot : float
        Photon-noise variance per unit of signal used in the weights (1 / gain).
    noise, background : float
        Background sigma and level of the frame.
    """

    params: NDArray[np.float64]
    cov: NDArray[np.float64]
    chi2_red: NDArray[np.float64]
    n_pixels: NDArray[np.int64]
    ok: NDArray[np.bool_]
    reasons: tuple[str, ...]
    label: NDArray[np.int32]
    shot: float
    noise: float
    background: float

    def __len__(self) -> int:
        return int(self.params.shape[0])

    @property
    def ends_xy(self) -> NDArray[np.float64]:
        """The two ends (K, 2, 2) of each arc, ``c - h`` then ``c + h`` (no time order)."""
        c, h = self.params[:, 0:2], self.params[:, 2:4]
        return np.stack([c - h, c + h], axis=1)

    @property
    def length_px(self) -> NDArray[np.float64]:
        return 2.0 * np.hypot(self.params[:, 2], self.params[:, 3])

    @property
    def blur_px(self) -> NDArray[np.float64]:
        return self.params[:, 8]

    @property
    def flux(self) -> NDArray[np.float64]:
        """The light of each streak, a sqrt(2 pi) s L (image units)."""
        return self.params[:, 5] * np.sqrt(2.0 * np.pi) * self.params[:, 8] * self.length_px

    @property
    def flux_snr(self) -> NDArray[np.float64]:
        """Amplitude over its 1-sigma."""
        return self.params[:, 5] / np.sqrt(np.maximum(self.cov[:, 5, 5], 1e-300))

    def measurements(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(m, C): the ends and light centroid m (K, 6) = (x1, y1, x2, y2, xc, yc) px and their
        covariance C (K, 6, 6) px^2 (module docstring)."""
        jac = measurement_jacobian(self.params)
        m = measurement(self.params)
        return m, np.einsum("kij,kjl,kml->kim", jac, self.cov, jac)

    def end_sigma_px(self) -> NDArray[np.float64]:
        """1-sigma (K, 2) of each end along its arc (px)."""
        _, cov = self.measurements()
        u = self.params[:, 2:4] / np.hypot(self.params[:, 2], self.params[:, 3])[:, None]
        var = [np.einsum("ki,kij,kj->k", u, cov[:, s, s], u) for s in (slice(0, 2), slice(2, 4))]
        return np.sqrt(np.maximum(np.stack(var, axis=1), 0.0))


def measurement(params: NDArray) -> NDArray[np.float64]:
    """(x1, y1, x2, y2, xc, yc) (K, 6) of arc parameters (K, 9) (module docstring)."""
    c, h, sag, g = params[:, 0:2], params[:, 2:4], params[:, 4], params[:, 6]
    half = np.hypot(h[:, 0], h[:, 1])
    n = np.stack([-h[:, 1], h[:, 0]], axis=1) / half[:, None]
    centroid = c + (g / 3.0)[:, None] * h + (2.0 * sag / 3.0)[:, None] * n
    return np.concatenate([c - h, c + h, centroid], axis=1)


def measurement_jacobian(params: NDArray) -> NDArray[np.float64]:
    """d measurement / d params, (K, 6, 9)."""
    k = len(params)
    h, sag, g = params[:, 2:4], params[:, 4], params[:, 6]
    half = np.hypot(h[:, 0], h[:, 1])
    u = h / half[:, None]
    n = np.stack([-u[:, 1], u[:, 0]], axis=1)
    eye = np.broadcast_to(np.eye(2), (k, 2, 2))
    jac = np.zeros((k, 6, NPAR))
    jac[:, 0:2, 0:2], jac[:, 0:2, 2:4] = eye, -eye
    jac[:, 2:4, 0:2], jac[:, 2:4, 2:4] = eye, eye
    jac[:, 4:6, 0:2] = eye
    dn_dh = -u[:, :, None] * n[:, None, :] / half[:, None, None]
    jac[:, 4:6, 2:4] = (g / 3.0)[:, None, None] * eye + (2.0 * sag / 3.0)[:, None, None] * dn_dh
    jac[:, 4:6, 4] = 2.0 * n / 3.0
    jac[:, 4:6, 6] = h / 3.0
    return jac


def saturation_level(image: NDArray) -> float:
    """The value an integer frame saturates at (its maximum, when that is 2^bits - 1 for a usual ADC
    depth), else inf."""
    if image.dtype.kind not in "ui" or image.size == 0:
        return np.inf
    top = int(image.max())
    return float(top) if any(top == 2**bits - 1 for bits in SATURATION_BITS) else np.inf


def fit_pixels(image: ArrayLike) -> tuple[NDArray[np.float64], float]:
    """The frame (H, W) as the contiguous float64 pixels the fits read, and its saturation level
    (:func:`saturation_level` of the frame as given): made once per frame, so that each of its
    fits does not copy the frame again (8 MB and about 2 ms for 1024 x 1024 px)."""
    raw = np.asarray(image)
    return np.ascontiguousarray(raw, dtype=np.float64), saturation_level(raw)


PROFILE_SNR = 6.0
"""The profile along a blob is smoothed until its mean level is this many noise sigmas."""
MIN_RUN_PX = 6
MAX_RUNS = 4


def first_guesses(image: NDArray, candidates: StreakCandidates, psf_sigma_px: float = 1.0):
    """Start parameters (K', 9), labels (K',), reach and band (K',) from candidate blobs.

    Along each blob's axis, the runs of :func:`.streak_kernel.profile_runs` (the pieces where the
    light per pixel of length is above half its plateau) give the ends to within a pixel or two;
    a blob of collinear streaks joined by the segmentation gives one guess per run (each one's
    window stops short of the next run). The amplitude comes from the plateau, the background
    is the sky's under the candidate (``StreakCandidates.sky``)."""
    rows, owners, reaches, bands = [], [], [], []
    runs = np.zeros((MAX_RUNS, 3))
    s0 = float(psf_sigma_px)
    img = np.ascontiguousarray(image, dtype=np.float64)
    for k in range(len(candidates)):
        c, u = candidates.centroid_xy[k], candidates.direction[k]
        lo, hi = candidates.extent_px[k]
        band = 2.5 * s0 + 0.5 + min(0.015 * (hi - lo), 4.0)
        found = kernel().profile_runs(img, c[0], c[1], u[0], u[1], lo - 4.0 * s0, hi + 4.0 * s0, band,
                                      candidates.sky[k], _smoothing(candidates, k, band), MIN_RUN_PX, runs)
        pieces = runs[:found].copy() if found else np.array([[lo + 2.0 * s0, hi - 2.0 * s0, np.nan]])
        for j, (t1, t2, plateau) in enumerate(pieces):
            half = max(0.5 * (t2 - t1), 1.0)
            density = plateau if np.isfinite(plateau) else candidates.flux[k] / max(2.0 * half, 1.0)
            rows.append([c[0] + 0.5 * (t1 + t2) * u[0], c[1] + 0.5 * (t1 + t2) * u[1], half * u[0], half * u[1], 0.0,
                         max(density, 0.0) / (np.sqrt(2.0 * np.pi) * s0), 0.0, candidates.sky[k], s0])
            before = pieces[j][0] - pieces[j - 1][1] if j else np.inf
            after = pieces[j + 1][0] - t2 if j + 1 < found else np.inf
            gaps = [before, after]
            reaches.append(min(4.0 * s0 + 3.0, max(0.5 * min(gaps), 1.5)))
            bands.append(3.0 * s0 + 2.0 + min(0.03 * half, 5.0))
            owners.append(candidates.label[k])
    if not rows:
        return np.zeros((0, NPAR)), np.zeros(0, dtype=np.int32), np.zeros(0), np.zeros(0)
    return np.array(rows), np.array(owners, dtype=np.int32), np.array(reaches), np.array(bands)


def _smoothing(candidates: StreakCandidates, k: int, band: float) -> int:
    """Profile smoothing (px, odd, 3-31) that puts blob k's mean light per pixel of length at
    :data:`PROFILE_SNR` sigmas of the smoothed profile."""
    lo, hi = candidates.extent_px[k]
    density = max(candidates.flux[k], 1e-9) / max(hi - lo, 1.0)
    sigma = candidates.noise * np.sqrt(2.0 * band + 1.0)
    width = int(np.clip(np.ceil((PROFILE_SNR * sigma / density) ** 2), 3, 31))
    return width | 1


def tight_window(params: NDArray) -> tuple[NDArray, NDArray]:
    """Reach and band (K,) of the second pass: 4 blurs + 2 px beyond the ends, 3 blurs + 1.5 px across."""
    s = np.clip(params[:, 8], *BLUR_RANGE_PX)
    return 4.0 * s + 2.0, 3.0 * s + 1.5


def fit_streaks(
    image: ArrayLike,
    start: ArrayLike,
    reach: ArrayLike,
    band: ArrayLike,
    *,
    noise: float,
    labels: NDArray | None = None,
    bin_px: int = 1,
    own: ArrayLike | None = None,
    shot: float | None = None,
    saturation: float | None = None,
    passes: int = 2,
    max_windows: int = MAX_WINDOWS,
    max_iter: int = MAX_ITER,
) -> StreakFits:
    """Fit arcs to a frame from first guesses (module docstring).

    Parameters
    ----------
    image : array_like, shape (H, W)
        The frame (counts).
    start : array_like, shape (K, 9)
        First guesses (:mod:`._streak_kernel` parameters; :func:`first_guesses`).
    reach, band : array_like, shape (K,)
        The first pass's window: px beyond each first guess's ends, px across its arc.
    noise : float
        Per-pixel background sigma (image units).
    labels, bin_px, own : optional
        Blob labels on a grid ``bin_px`` times coarser and each guess's own label: pixels of
        other blobs are left out of a window.
    shot : float, optional
        Photon-noise variance per unit of signal (1 / gain); None estimates it from the first
        pass (with one pass: background noise only).
    saturation : float, optional
        Pixels at or above it are left out; None: :func:`saturation_level`.
    passes : int
        2 (module docstring) or 1: only the second pass, in the tight window around ``start``
        (a first guess within a pixel or so, such as a prediction), its weights from ``start``.
    max_windows : int
        Windows a fit may move through when an end walks to its window's edge (1: a fit stays in
        the window around ``start``, as a prediction's must to agree with it).
    max_iter : int
        Levenberg-Marquardt iterations per window and pass; a fit that has not converged by then
        is refused ("the fit did not converge").

    Returns
    -------
    StreakFits
    """
    raw = np.asarray(image)
    if raw.ndim != 2:
        raise InvalidInputError(f"image must be 2-D, got shape {raw.shape}")
    img = np.ascontiguousarray(raw, dtype=np.float64)
    start = np.ascontiguousarray(start, dtype=np.float64).reshape(-1, NPAR)
    k = len(start)
    labels = np.zeros((1, 1), dtype=np.int32) if labels is None else np.ascontiguousarray(labels, dtype=np.int32)
    own = np.zeros(k, dtype=np.int32) if own is None else np.ascontiguousarray(own, dtype=np.int32)
    sat = saturation_level(raw) if saturation is None else float(saturation)
    var_bg = float(noise) ** 2
    if not var_bg > 0:
        raise InvalidInputError(f"noise must be a positive sigma, got {noise!r}")
    reach, band = np.asarray(reach, dtype=float), np.asarray(band, dtype=float)
    _check_count(max_windows, "max_windows", "windows")
    _check_count(max_iter, "max_iter", "iterations")
    stopping = (TOL_PX, STEP_SIGMAS, max_windows, max_iter)
    if passes == 1:
        params, cov, stats = _run(img, labels, bin_px, own, start, reach, band, sat, var_bg, shot or 0.0, False,
                                  stopping)
        return _judged(params, cov, stats, img.shape, own, shot or 0.0, float(noise), _median_bg(start))
    params, cov, stats = _run(img, labels, bin_px, own, start, reach, band, sat, var_bg, shot or 0.0, True,
                              (FIRST_TOL_PX, FIRST_STEP_SIGMAS, max_windows, max_iter))
    # a first pass that ran out of steps may still be a streak: its background-only weights make a
    # bright streak's photon noise look like misfit, which the second pass's weights remove
    flags = np.where(stats[:, 3] == 1, 0, stats[:, 3]).astype(int)
    promising = np.array([not reason for reason in verdicts(params, cov, flags, img.shape)], dtype=bool)
    tight_reach, tight_band = tight_window(params)
    if shot is None:
        shot = estimate_shot(img, labels, bin_px, own, params, tight_reach, tight_band, sat, var_bg, promising)
    again = np.flatnonzero(promising)
    if again.size:
        second = _run(img, labels, bin_px, own[again], params[again], tight_reach[again], tight_band[again], sat,
                      var_bg, shot, False, stopping)
        params[again], cov[again], stats[again] = second
    return _judged(params, cov, stats, img.shape, own, shot, float(noise), _median_bg(start))


def _check_count(value: object, name: str, what: str) -> None:
    """Refuse a ``value`` that is not a whole number of at least 1 (``what``: its unit, for the message)."""
    if not (isinstance(value, int | np.integer) and not isinstance(value, bool) and value >= 1):
        raise InvalidInputError(f"{name} must be a whole number of {what}, at least 1, got {value!r}")


def _median_bg(start: NDArray) -> float:
    return float(np.median(start[:, 7])) if len(start) else 0.0


def _run(img, labels, bin_px, own, start, reach, band, sat, var_bg, shot, half, stopping):
    """One pass of the compiled fit; ``stopping`` is (tol_px, step_sigmas, max_windows, max_iter)."""
    tol_px, step_sigmas, max_windows, max_iter = stopping
    k = len(start)
    params, covs, stats = np.zeros((k, NPAR)), np.zeros((k, NPAR, NPAR)), np.zeros((k, 4))
    kernel().fit_arcs(img, labels, int(bin_px), own, np.ascontiguousarray(start, dtype=np.float64),
                      np.ascontiguousarray(reach, dtype=np.float64), np.ascontiguousarray(band, dtype=np.float64),
                      sat, var_bg, float(shot), bool(half), int(max_iter), float(tol_px), float(step_sigmas),
                      int(max_windows), CAPACITY, params, covs, stats)
    return params, covs, stats


SHOT_STREAKS = 6
"""The photon noise is estimated from the residuals of this many of the brightest clean first fits."""


def estimate_shot(img, labels, bin_px, own, fitted, reach, band, sat, var_bg, good) -> float:
    """Photon-noise variance per unit of signal from the residuals of the brightest clean fits (>= 0)."""
    index = np.flatnonzero(good)
    if index.size == 0:
        return 0.0
    index = index[np.argsort(-fitted[index, 5], kind="stable")][:SHOT_STREAKS]
    num, den = kernel().shot_sums(img, labels, int(bin_px), own[index], np.ascontiguousarray(fitted[index]),
                                  np.ascontiguousarray(reach[index]), np.ascontiguousarray(band[index]), sat, var_bg,
                                  CAPACITY)
    return max(num / den, 0.0) if den > 0 else 0.0


def _judged(params, cov, stats, shape, own, shot, noise, background) -> StreakFits:
    """The fits with their quality verdicts (:func:`verdict`) and chi-square-scaled covariances."""
    n = stats[:, 1].astype(np.int64)
    chi2_red = stats[:, 0] / np.maximum(n - NPAR, 1)
    cov = cov * np.maximum(chi2_red, 1.0)[:, None, None]
    reasons = verdicts(params, cov, stats[:, 3], shape)
    ok = np.array([not r for r in reasons], dtype=bool)
    return StreakFits(params, cov, chi2_red, n, ok, reasons, own.copy(), float(shot), noise, background)


FLAG_REASONS = ("", "the fit did not converge", "too few pixels near the streak", "singular fit")
"""Why a fit is not a clean streak, by the kernel's flag (:data:`._streak_kernel.FIT_OK` ...)."""


def verdicts(params: NDArray, cov: NDArray, flags: NDArray, shape: tuple[int, int]) -> tuple[str, ...]:
    """Why each of K fits (params (K, 9), cov (K, 9, 9), kernel flags (K,)) is not a clean
    streak of a frame of ``shape`` ("" when it is); the first test a fit fails names it."""
    p, flags = np.asarray(params, dtype=float).reshape(-1, NPAR), np.asarray(flags, dtype=int)
    length, blur = 2.0 * np.hypot(p[:, 2], p[:, 3]), p[:, 8]
    with np.errstate(invalid="ignore"):
        faint = ~(p[:, 5] > MIN_FLUX_SNR * np.sqrt(np.maximum(cov[:, 5, 5], 0.0)))
        ends = np.stack([p[:, 0:2] - p[:, 2:4], p[:, 0:2] + p[:, 2:4]], axis=1)
        margin = (EDGE_MARGIN_SIGMAS * blur)[:, None, None]
        border = np.any((ends < margin) | (ends > np.array([shape[1], shape[0]]) - 1 - margin), axis=(1, 2))
        spread = np.maximum(cov[:, 0, 0] + cov[:, 2, 2], cov[:, 1, 1] + cov[:, 3, 3])
        vague = ~((spread >= 0.0) & (spread <= MAX_END_SIGMA_PX**2))  # NaN or a negative variance: singular
        bad_blur = ~((blur >= BLUR_RANGE_PX[0]) & (blur <= BLUR_RANGE_PX[1]))
    short = length < MIN_LENGTH_PX
    failed = (flags != 0) | bad_blur | short | faint | border | vague
    return tuple(_reason(int(flags[i]), blur[i], length[i], (bad_blur[i], short[i], faint[i], border[i]))
                 if failed[i] else "" for i in range(len(p)))


def _reason(flag: int, blur: float, length: float, tests: tuple[bool, bool, bool, bool]) -> str:
    """The message of a fit that fails :func:`verdicts`: the first of its kernel flag and its
    failed ``tests`` (bad blur, too short, too faint, at the border; else its ends are vague)."""
    bad_blur, short, faint, border = tests
    if flag != 0:
        return FLAG_REASONS[flag]
    if bad_blur:
        return f"fitted blur {blur:.2f} px: not one star's streak"
    if short:
        return f"streak {length:.1f} px long, shorter than {MIN_LENGTH_PX:g} px"
    if faint:
        return "too faint"
    if border:
        return "an end at the image border: the star entered or left the field"
    return f"ends less precise than {MAX_END_SIGMA_PX:g} px"
