"""Streaks predicted from an attitude and a rate: the catalog stars of the field, their arcs as
first guesses of the streak fit, and which fits agree with the prediction.

Used twice: after a lost-in-space identification, to fit the streaks of every other bright star
of the field (whether the segmentation found it or not), and in tracking (:mod:`._streak_track`),
where the previous frame's attitude and rate predict every streak of the new one (Samaan 2002 Eq. 1–3:
windows around the predicted positions only). A predicted streak is skipped when another
predicted star's path passes within :data:`CROWDED_PX` of it (their light would mix in one
window).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..catalog import load_catalog
from ..identify import FieldStars
from ._streak_fit import MAX_ITER, MAX_WINDOWS, NPAR, StreakFits, fit_streaks
from ._streak_model import Timing, predict

CROWDED_PX = 6.0
"""Predicted paths closer than this (px, plus the blurs) are left out as blends."""
PATH_SAMPLES = 9
EDGE_PX = 4.0
"""A predicted streak must stay this far inside the image (px, plus 3 blurs)."""
MIN_PREDICTED_SNR = 20.0
"""Predicted streaks fainter than this (matched-filter SNR of their expected light) are not fitted."""
CONTAMINATION_SNR = 5.0
"""Stars at least this bright (expected SNR) count as neighbours that crowd a predicted streak."""
PREDICTED_MAX_ITER = 10
MAX_PREDICTED_TURN_RAD = math.pi
"""No streak is predicted when the camera turns more than half a turn in the exposure (a wrong
exposure time, or rate): a star's path then folds back on itself or crosses the whole sky, and no
single streak of it can be fitted; beyond about 1e300 s the arithmetic overflows."""
"""Iterations of a one-pass fit from a close prediction (within a pixel or so). On 40 profiling
frames 92 % of such fits converged within this many; the others, mostly faint or blended streaks
whose ends creep along the arc (the chi-square falling by about 0.1 a step), took 42 % of the
stage's pixel iterations, and 57 % of them were refused in the end anyway."""


def streak_snr(flux: NDArray, length_px: NDArray, blur_px: float, noise: float) -> NDArray[np.float64]:
    """Matched-filter signal-to-noise ratio of streaks of light ``flux`` (image units), length
    and blur (px) over a background of per-pixel sigma ``noise``: ``F / (noise sqrt(2 sqrt(pi) s L))``
    (the line's light per pixel of length over the noise, times the root of the pixels it spans)."""
    return np.asarray(flux, dtype=float) / (noise * np.sqrt(2.0 * np.sqrt(np.pi) * blur_px
                                                           * np.maximum(np.asarray(length_px, dtype=float), 1.0)))


def field_catalog(stars: FieldStars, camera: Camera, rot_mid: Rotation, turn_rad: float) -> NDArray[np.int64]:
    """Indices into ``stars.rows`` (brightest first) of the stars within the field's radius plus
    ``turn_rad`` of the boresight."""
    boresight = rot_mid.inv().apply([0.0, 0.0, 1.0])
    half_diag = math.atan(math.hypot(camera.width, camera.height) / (2.0 * camera.fx))
    return np.sort(stars.near(boresight, half_diag + turn_rad))


def inside(predicted: NDArray, camera: Camera, margin_px: float) -> NDArray[np.bool_]:
    """Streaks (K, 6 predictions) whose two ends lie ``margin_px`` inside the image."""
    ends = predicted[:, 0:4].reshape(-1, 2, 2)
    x, y = ends[..., 0], ends[..., 1]
    ok = (x >= margin_px) & (y >= margin_px) & (x <= camera.width - 1 - margin_px)
    ok &= y <= camera.height - 1 - margin_px
    return np.all(ok, axis=1) & np.all(np.isfinite(predicted), axis=1)


def _path_points(predicted: NDArray) -> NDArray[np.float64]:
    """Points (K, S, 2) along each predicted chord."""
    f = np.linspace(0.0, 1.0, PATH_SAMPLES)[None, :, None]
    return predicted[:, None, 0:2] * (1 - f) + predicted[:, None, 2:4] * f


def crowded(predicted: NDArray, candidates: NDArray, neighbours: NDArray, blur_px: float) -> NDArray[np.bool_]:
    """Which ``candidates`` (indices into the predictions (S, 6)) have a sampled path within
    :data:`CROWDED_PX` + 4 blurs of the path of another star of ``neighbours`` (indices)."""
    if candidates.size == 0 or neighbours.size < 2:
        return np.zeros(candidates.size, dtype=bool)
    near = cKDTree(_path_points(predicted[candidates]).reshape(-1, 2)).sparse_distance_matrix(
        cKDTree(_path_points(predicted[neighbours]).reshape(-1, 2)), CROWDED_PX + 4.0 * blur_px,
        output_type="ndarray")
    mine = near["i"] // PATH_SAMPLES  # the candidate of each close pair's first point
    other = neighbours[near["j"] // PATH_SAMPLES] != candidates[mine]
    return np.bincount(mine[other], minlength=candidates.size) > 0


def guesses(predicted: NDArray, image: NDArray, background: float, blur_px: float,
            slack_px: float) -> tuple[NDArray, NDArray, NDArray]:
    """First guesses (K, 9), reach and band (K,) of predicted streaks: the arc through the
    predicted ends and centroid, the amplitude from the image along the path, a window widened
    by ``slack_px`` (the prediction's uncertainty)."""
    e1, e2, cen = predicted[:, 0:2], predicted[:, 2:4], predicted[:, 4:6]
    c, h = 0.5 * (e1 + e2), 0.5 * (e2 - e1)
    half = np.maximum(np.hypot(h[:, 0], h[:, 1]), 0.5)
    u = h / half[:, None]
    n = np.stack([-u[:, 1], u[:, 0]], axis=1)
    start = np.zeros((len(predicted), NPAR))
    start[:, 0:2], start[:, 2:4] = c, h
    start[:, 4] = 1.5 * np.sum((cen - c) * n, axis=1)
    start[:, 5] = np.maximum(_level(image, e1, e2, background), 0.0)
    start[:, 7], start[:, 8] = background, blur_px
    reach = np.full(len(predicted), 4.0 * blur_px + 2.0 + slack_px)
    band = np.full(len(predicted), 3.0 * blur_px + 1.0 + slack_px)
    return start, reach, band


def _level(image: NDArray, e1: NDArray, e2: NDArray, background: float) -> NDArray[np.float64]:
    """Median pixel value above the background along each chord (K,), from 15 samples."""
    f = np.linspace(0.1, 0.9, 15)[None, :, None]
    pts = np.rint(e1[:, None, :] * (1 - f) + e2[:, None, :] * f).astype(np.intp)
    x = np.clip(pts[..., 0], 0, image.shape[1] - 1)
    y = np.clip(pts[..., 1], 0, image.shape[0] - 1)
    return np.median(image[y, x], axis=1) - background


def agreement_px(fits: StreakFits, predicted: NDArray) -> NDArray[np.float64]:
    """Largest distance (K,) of a fit's ends and centroid from the prediction (ends either way round)."""
    m = fits.measurements()[0]
    swapped = m[:, [2, 3, 0, 1, 4, 5]]
    def worst(a):
        return np.max(np.linalg.norm((a - predicted).reshape(-1, 3, 2), axis=2), axis=1)
    return np.minimum(worst(m), worst(swapped))


def fit_predicted(image: NDArray, camera: Camera, stars_icrs: NDArray, rot_mid: Rotation, omega: NDArray,
                  alpha: NDArray, timing: Timing, *, noise: float, background: float, blur_px: float,
                  shot: float | None, slack_px: float, tolerance_px: float, limit: int,
                  flux: NDArray | None = None, wanted: NDArray | None = None, passes: int = 1,
                  saturation: float | None = None) -> tuple[NDArray[np.intp], StreakFits | None]:
    """Fit the streaks of the first ``limit`` stars (S, 3, brightest first) predicted by
    (rot_mid, omega, alpha) that are ``wanted`` (S,) (default all: not measured yet), inside the
    image, not crowded by another star of the S (with ``flux``, one of at least
    :data:`CONTAMINATION_SNR`) and, given each star's expected light ``flux`` (S,), at least
    :data:`MIN_PREDICTED_SNR`; returns the star indices fitted and their fits (``passes`` of
    :func:`.streak_fit.fit_streaks`: one from a close prediction, which stays in the window
    around it, two from a rough one, which may move its window), each fit's ``ok`` also requiring
    it to agree with the prediction within ``tolerance_px``. ``saturation`` is
    :func:`.streak_fit.fit_streaks`'s (None: from ``image``). Nothing is fitted when the camera
    turns more than :data:`MAX_PREDICTED_TURN_RAD` in the exposure."""
    if not float(np.linalg.norm(omega)) * timing.exposure_s <= MAX_PREDICTED_TURN_RAD:
        return np.zeros(0, dtype=np.intp), None
    predicted = predict(camera, rot_mid, omega, alpha, stars_icrs, timing)
    use = inside(predicted, camera, EDGE_PX + 3.0 * blur_px)
    if wanted is not None:
        use &= np.asarray(wanted, dtype=bool)
    neighbours = np.all(np.isfinite(predicted), axis=1)
    if flux is not None:
        length = np.linalg.norm(predicted[:, 2:4] - predicted[:, 0:2], axis=1)
        snr = streak_snr(flux, length, blur_px, noise)
        use &= snr >= MIN_PREDICTED_SNR
        neighbours &= snr >= CONTAMINATION_SNR
    index = np.flatnonzero(use)[: 2 * limit]
    index = index[~crowded(predicted, index, np.flatnonzero(neighbours | use), blur_px)][:limit]
    if index.size == 0:
        return index, None
    start, reach, band = guesses(predicted[index], image, background, blur_px, slack_px)
    fits = fit_streaks(image, start, reach, band, noise=noise, shot=shot, passes=passes,
                       max_windows=1 if passes == 1 else MAX_WINDOWS, saturation=saturation,
                       max_iter=PREDICTED_MAX_ITER if passes == 1 else MAX_ITER)
    agree = agreement_px(fits, predicted[index]) <= tolerance_px
    reasons = tuple(r or ("" if a else "does not agree with the predicted streak")
                    for r, a in zip(fits.reasons, agree, strict=True))
    return index, replace(fits, ok=fits.ok & agree, reasons=reasons)


@dataclass(frozen=True)
class Identified:
    """The streaks of a frame known to be catalog stars: rows ``rows`` (K,) of ``fits``, with
    their stars' ICRS vectors (K, 3) and Hipparcos numbers (K,)."""

    fits: StreakFits
    rows: NDArray[np.int64]
    stars: NDArray[np.float64]
    hips: NDArray[np.int64]

    def measurements(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The identified streaks' measurements (K, 6) and covariances (K, 6, 6)."""
        measured, cov = self.fits.measurements()
        return measured[self.rows], cov[self.rows]

    def joined(self, more: StreakFits, stars: NDArray, hips: NDArray) -> Identified:
        """With the clean fits of ``more`` (whose stars are ``stars``, ``hips``, one per fit) added."""
        ok = np.flatnonzero(more.ok)
        return Identified(concatenated(self.fits, more), np.concatenate([self.rows, len(self.fits) + ok]),
                          np.concatenate([self.stars, stars[ok]]), np.concatenate([self.hips, hips[ok]]))


def concatenated(a: StreakFits, b: StreakFits) -> StreakFits:
    """The fits of ``a`` then ``b`` (the frame's noise figures from ``a``)."""
    return StreakFits(np.concatenate([a.params, b.params]), np.concatenate([a.cov, b.cov]),
                      np.concatenate([a.chi2_red, b.chi2_red]), np.concatenate([a.n_pixels, b.n_pixels]),
                      np.concatenate([a.ok, b.ok]), a.reasons + b.reasons, np.concatenate([a.label, b.label]),
                      a.shot, a.noise, a.background)


def v_mags(hips: NDArray) -> NDArray[np.float64]:
    """V magnitudes (K,) of Hipparcos numbers (K,)."""
    catalog = load_catalog()
    order = np.argsort(catalog.hip)
    return catalog.v_mag[order[np.searchsorted(catalog.hip, hips, sorter=order)]]


def zero_point(flux: NDArray, v_mag: NDArray) -> float:
    """Light (image units) of a V = 0 star in this frame: the median over identified streaks of
    ``flux 10^(0.4 V)`` (colours and vignetting make each star's differ by some 10 %); 0 when none."""
    good = np.isfinite(v_mag) & (flux > 0)
    return float(np.median(flux[good] * 10.0 ** (0.4 * v_mag[good]))) if np.any(good) else 0.0


@dataclass(frozen=True)
class Field:
    """The catalog stars around a boresight (indices into ``stars.rows``, brightest first), their
    ICRS vectors (S, 3), Hipparcos numbers and V magnitudes (S,)."""

    vectors: NDArray[np.float64]
    hips: NDArray[np.int64]
    v_mag: NDArray[np.float64]

    @classmethod
    def around(cls, stars: FieldStars, camera: Camera, rot_mid: Rotation, turn_rad: float) -> Field:
        near = field_catalog(stars, camera, rot_mid, turn_rad)
        catalog = load_catalog()
        rows = stars.rows[near]
        return cls(stars.vectors[near], catalog.hip[rows], catalog.v_mag[rows])

    def flux(self, zero: float) -> NDArray[np.float64] | None:
        """Expected light of each star for a zero point (None when it is not known)."""
        return zero * 10.0 ** (-0.4 * self.v_mag) if zero > 0 else None
