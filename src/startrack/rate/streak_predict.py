"""Streaks predicted from an attitude and a rate: the catalog stars of the field, their arcs as
first guesses of the streak fit, and which fits agree with the prediction.

Used twice: after a lost-in-space identification, to fit the streaks of every other bright star
of the field (whether the segmentation found it or not), and in tracking (:mod:`.streak_track`),
where the previous frame's attitude and rate predict every streak of the new one (seed 004 §2.2:
windows around the predicted positions only). A predicted streak is skipped when another
predicted star's path passes within :data:`CROWDED_PX` of it (their light would mix in one
window).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..identify.field_stars import FieldStars
from .streak_fit import NPAR, StreakFits, fit_streaks
from .streak_model import Timing, predict

CROWDED_PX = 6.0
"""Predicted paths closer than this (px, plus the blurs) are left out as blends."""
PATH_SAMPLES = 9
EDGE_PX = 4.0
"""A predicted streak must stay this far inside the image (px, plus 3 blurs)."""


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


def crowded(predicted: NDArray, blur_px: float) -> NDArray[np.bool_]:
    """Streaks (K,) whose sampled path comes within :data:`CROWDED_PX` + 4 blurs of another's."""
    k = len(predicted)
    if k < 2:
        return np.zeros(k, dtype=bool)
    f = np.linspace(0.0, 1.0, PATH_SAMPLES)[None, :, None]
    paths = predicted[:, None, 0:2] * (1 - f) + predicted[:, None, 2:4] * f  # (K, S, 2), chords
    flat = paths.reshape(-1, 2)
    dist = np.linalg.norm(flat[:, None, :] - flat[None, :, :], axis=2).reshape(k, PATH_SAMPLES, k, PATH_SAMPLES)
    nearest = dist.min(axis=(1, 3))
    np.fill_diagonal(nearest, np.inf)
    return nearest.min(axis=1) < CROWDED_PX + 4.0 * blur_px


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
    band = np.full(len(predicted), 3.5 * blur_px + 1.5 + slack_px)
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
                  shot: float | None, slack_px: float, tolerance_px: float, limit: int
                  ) -> tuple[NDArray[np.intp], StreakFits | None]:
    """Fit the streaks of the first ``limit`` stars (S, 3) predicted by (rot_mid, omega, alpha)
    inside the image and not crowded; returns the star indices fitted and their fits, each
    fit's ``ok`` also requiring it to agree with the prediction within ``tolerance_px``."""
    predicted = predict(camera, rot_mid, omega, alpha, stars_icrs, timing)
    use = inside(predicted, camera, EDGE_PX + 3.0 * blur_px)
    use[use] = ~crowded(predicted[use], blur_px)
    index = np.flatnonzero(use)[:limit]
    if index.size == 0:
        return index, None
    start, reach, band = guesses(predicted[index], image, background, blur_px, slack_px)
    fits = fit_streaks(image, start, reach, band, noise=noise, shot=shot)
    agree = agreement_px(fits, predicted[index]) <= tolerance_px
    reasons = tuple(r or ("" if a else "does not agree with the predicted streak")
                    for r, a in zip(fits.reasons, agree, strict=True))
    return index, replace(fits, ok=fits.ok & agree, reasons=reasons)
