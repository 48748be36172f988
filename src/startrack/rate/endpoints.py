"""Streak endpoint detectors and sub-pixel endpoint localisation.

Seed 001 §3 eqs. 3.1-3.16 (notes seed-001-004 §1.11-1.15). A streak's two ends respond like
corners, so a cornerness map over its region of interest (ROI) has two peaks:

- gradients with the 3 x 3 derivative-of-Gaussian kernel, sigma 0.5 (eq. 3.4; the samples of
  ``-(x / s^2) G`` at integer offsets, not renormalised);
- the structure tensor ``[[Ix^2, IxIy], [IxIy, Iy^2]]`` averaged over a Gaussian window of
  ``integration_sigma_px`` (needed, though the seed does not say so: unaveraged, its
  determinant is zero everywhere);
- **minimum eigenvalue** (Shi-Tomasi, eq. 3.5-3.6) ``(a + c)/2 - sqrt(((a - c)/2)^2 + b^2)``;
- **Harris** (eq. 3.8) ``det - k tr^2`` (the seed's k = 0.15 is :data:`SEED_HARRIS_K`; the
  default k = 0.04 measured better here);
- **Trajkovic-4 / -8** (eqs. 3.9-3.13, Trajkovic and Hedley 1998): the simple cornerness
  ``min_lines r`` over the lines through the pixel (horizontal and vertical; plus the two
  diagonals for 8 neighbours), ``r = (I_A - I_C)^2 + (I_A' - I_C)^2``, refined by the
  inter-pixel approximation between adjacent lines (with the index of eq. 3.12 corrected, notes
  §7 item 9). The seed's two-resolution candidate search is a speed-up that a single ROI does
  not need, so the cornerness is computed at full resolution on the (lightly smoothed) ROI.

Localisation (eqs. 3.14-3.16): non-maximum suppression (strictly greater than the 8
neighbours) above a fraction of the ROI's strongest response; one clean streak must give exactly
two peaks (more: noise, overlapping streaks or a non-star; here extra peaks along the line between
the two outermost are accepted as false corners on the streak's body, others reject the ROI);
then the centre of intensity of the clipped cornerness
in a (2N + 1)^2 window, with the coordinate weights eq. 3.15 omits (notes §7 item 10).

Every Gaussian smoothing pulls the peaks inward along the streak (seed 001 p.40): a constant
``bias_px`` for a camera and detector, removed by moving both ends outward along the streak
(:func:`calibrate_bias` measures it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from ..errors import InvalidInputError

DETECTORS = ("harris", "min_eigenvalue", "trajkovic4", "trajkovic8")
SEED_HARRIS_K = 0.15
"""Seed 001's hand-tuned Harris constant (p.24)."""
HARRIS_K = 0.04
"""Our default: with a 1-pixel integration window it gives endpoints about 1.5x more precise
than the seed's 0.15 on our simulated streaks (benchmarks/streak_benchmark.py, docs)."""
INTEGRATION_SIGMA_PX = 1.0
HALF_WINDOW_PX = 2


def gaussian_derivative_kernel(sigma_px: float = 0.5, radius_px: int = 1) -> NDArray[np.float64]:
    """The x-derivative kernel ``-(x / s^2) G(x, y)`` (2r + 1, 2r + 1), rows = y, seed eq. 3.4.

    Correlating an image with it gives dI/dx (up to the Gaussian's blur); its transpose gives
    dI/dy. With the defaults the middle row is ``[0.3446, 0, -0.3446]`` in magnitude.
    """
    offsets = np.arange(-radius_px, radius_px + 1, dtype=float)
    x = offsets[None, :]
    y = offsets[:, None]
    g = np.exp(-(x**2 + y**2) / (2 * sigma_px**2)) / (2 * np.pi * sigma_px**2)
    return x / sigma_px**2 * g  # correlation with +x/s^2 G is convolution with -x/s^2 G


def structure_tensor(roi: NDArray[np.float64], derivative_sigma_px: float = 0.5,
                     integration_sigma_px: float = INTEGRATION_SIGMA_PX) -> tuple[NDArray, NDArray, NDArray]:
    """Window-averaged Ix^2, IxIy, Iy^2 of an image (each the image's shape)."""
    kernel = gaussian_derivative_kernel(derivative_sigma_px)
    ix = ndimage.correlate(roi, kernel, mode="nearest")
    iy = ndimage.correlate(roi, kernel.T, mode="nearest")
    smooth = lambda a: ndimage.gaussian_filter(a, integration_sigma_px, mode="nearest")  # noqa: E731
    return smooth(ix * ix), smooth(ix * iy), smooth(iy * iy)


def harris_response(roi: NDArray[np.float64], k: float = HARRIS_K, **tensor) -> NDArray[np.float64]:
    """Harris cornerness ``det A - k (tr A)^2`` (seed 001 eq. 3.8)."""
    a, b, c = structure_tensor(roi, **tensor)
    return a * c - b * b - k * (a + c) ** 2


def min_eigenvalue_response(roi: NDArray[np.float64], **tensor) -> NDArray[np.float64]:
    """Shi-Tomasi cornerness, the smaller eigenvalue of the structure tensor (eqs. 3.5-3.6)."""
    a, b, c = structure_tensor(roi, **tensor)
    return 0.5 * (a + c) - np.sqrt((0.5 * (a - c)) ** 2 + b * b)


_LINES4 = [((0, 1), (0, -1)), ((1, 0), (-1, 0))]  # (dy, dx) of A and A': horizontal, vertical
_LINES8 = [((0, 1), (0, -1)), ((1, 1), (-1, -1)), ((1, 0), (-1, 0)), ((1, -1), (-1, 1))]


def _shift(img: NDArray, dy: int, dx: int) -> NDArray:
    """I[y + dy, x + dx] with edge replication, same shape."""
    padded = np.pad(img, 1, mode="edge")
    h, w = img.shape
    return padded[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w]


def _interpixel(c, a, a2, b, b2) -> NDArray:
    """Trajkovic's inter-pixel cornerness between lines (A, A') and (B, B') through C."""
    r_a = (a - c) ** 2 + (a2 - c) ** 2
    r_b = (b - c) ** 2 + (b2 - c) ** 2
    b1 = (b - a) * (a - c) + (b2 - a2) * (a2 - c)
    bb = np.minimum(b1, (b - a2) * (a2 - c) + (b2 - a) * (a - c))
    aa = r_b - r_a - 2.0 * bb
    refined = np.where((bb < 0) & (aa + bb > 0), r_a - bb**2 / np.where(aa != 0, aa, 1.0), np.minimum(r_a, r_b))
    return refined


def trajkovic_response(roi: NDArray[np.float64], neighbours: int = 4, smooth_sigma_px: float = 1.0) -> NDArray:
    """Trajkovic cornerness with 4 or 8 neighbours (module docstring), on a smoothed ROI."""
    if neighbours not in (4, 8):
        raise InvalidInputError(f"neighbours must be 4 or 8, got {neighbours!r}")
    img = ndimage.gaussian_filter(roi, smooth_sigma_px, mode="nearest") if smooth_sigma_px > 0 else roi
    lines = _LINES4 if neighbours == 4 else _LINES8
    ends = [(_shift(img, *p), _shift(img, *q)) for p, q in lines]
    pairs = [(ends[i], ends[(i + 1) % len(ends)]) for i in range(len(ends) if neighbours == 8 else 1)]
    return np.min([_interpixel(img, a, a2, b, b2) for (a, a2), (b, b2) in pairs], axis=0)


def cornerness(roi: ArrayLike, detector: str = "harris", **params) -> NDArray[np.float64]:
    """Cornerness map of a background-subtracted ROI for one of :data:`DETECTORS`."""
    img = np.asarray(roi, dtype=float)
    if detector == "harris":
        return harris_response(img, **params)
    if detector == "min_eigenvalue":
        return min_eigenvalue_response(img, **params)
    if detector in ("trajkovic4", "trajkovic8"):
        return trajkovic_response(img, neighbours=int(detector[-1]), **params)
    raise InvalidInputError(f"detector must be one of {', '.join(DETECTORS)}, got {detector!r}")


def local_maxima(response: NDArray[np.float64], min_fraction: float) -> tuple[NDArray, NDArray]:
    """Rows and columns of strict 3 x 3 maxima above ``min_fraction`` of the largest, strongest first."""
    neighbour_max = ndimage.maximum_filter(np.where(np.isfinite(response), response, -np.inf),
                                           footprint=np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1]]), mode="nearest")
    top = np.max(response)
    peaks = (response > neighbour_max) & (response >= min_fraction * top) & (response > 0)
    rows, cols = np.nonzero(peaks)
    order = np.argsort(-response[rows, cols])
    return rows[order], cols[order]


def subpixel_peak(values: NDArray[np.float64], row: int, col: int, half: int = 1) -> NDArray[np.float64]:
    """Centre of intensity (x, y) of ``max(values, 0)`` in a (2 half + 1)^2 window (eq. 3.15)."""
    r0, r1 = max(row - half, 0), min(row + half + 1, values.shape[0])
    c0, c1 = max(col - half, 0), min(col + half + 1, values.shape[1])
    window = np.clip(values[r0:r1, c0:c1], 0.0, None)
    total = window.sum()
    if total <= 0:
        return np.array([col, row], dtype=float)
    ys, xs = np.mgrid[r0:r1, c0:c1]
    return np.array([(window * xs).sum() / total, (window * ys).sum() / total])


@dataclass(frozen=True)
class Endpoints:
    """The two ends of one streak, or why they were not found.

    ``xy`` (2, 2) holds the two ends (x, y) in full-image pixels (NaN when not ok), in no
    particular time order; ``peaks`` is the number of cornerness maxima found.
    """

    ok: bool
    xy: NDArray[np.float64]
    peaks: int
    reason: str = ""


def _failed(peaks: int, reason: str) -> Endpoints:
    return Endpoints(False, np.full((2, 2), np.nan), peaks, reason)


def _extreme_pair(points: NDArray[np.float64], line_tolerance_px: float) -> tuple[int, int] | None:
    """Indices of the two peaks farthest apart along their common line, or None if some peak is
    off the line through them by more than the tolerance (a crossing or a non-star)."""
    span = points[:, None, :] - points[None, :, :]
    i, j = np.unravel_index(np.argmax(np.sum(span**2, axis=-1)), span.shape[:2])
    axis = points[j] - points[i]
    axis /= np.linalg.norm(axis)
    offsets = (points - points[i]) @ np.array([-axis[1], axis[0]])
    return (int(i), int(j)) if np.max(np.abs(offsets)) <= line_tolerance_px else None


def locate_endpoints(
    roi: ArrayLike,
    origin_xy: ArrayLike = (0.0, 0.0),
    detector: str = "harris",
    *,
    half_window_px: int = HALF_WINDOW_PX,
    min_fraction: float = 0.1,
    line_tolerance_px: float = 3.0,
    bias_px: float = 0.0,
    min_separation_px: float = 3.0,
    **params,
) -> Endpoints:
    """The two endpoints of the streak in a background-subtracted ROI.

    Parameters
    ----------
    roi : array_like, shape (h, w)
        Background-subtracted pixels of one streak.
    origin_xy : array_like, shape (2,)
        Full-image (x, y) of ``roi[0, 0]``.
    detector : str
        One of :data:`DETECTORS`; ``params`` go to it (k, integration_sigma_px, ...).
    half_window_px : int
        N of the (2N + 1)^2 sub-pixel window.
    min_fraction : float
        Peaks below this fraction of the strongest are ignored.
    line_tolerance_px : float
        With more than two peaks (false corners along the body of a long or diagonal streak),
        the two farthest apart are the ends, provided every other peak lies within this
        distance of the line between them; otherwise (a crossing, a non-star) the ROI is
        rejected, as the seed rejects every ROI with more than two peaks.
    bias_px : float
        Calibrated inward bias; both ends are moved outward by it along the streak.
    min_separation_px : float
        Two peaks closer than this are not a streak (a point star).

    Returns
    -------
    Endpoints
        ``ok`` False with a reason for fewer than two peaks, peaks off one line, or peaks too
        close together.
    """
    img = np.asarray(roi, dtype=float)
    response = cornerness(img, detector, **params)
    rows, cols = local_maxima(response, min_fraction)
    if len(rows) < 2:
        return _failed(len(rows), "fewer than two cornerness peaks")
    pair = _extreme_pair(np.column_stack([cols, rows]).astype(float), line_tolerance_px)
    if pair is None:
        return _failed(len(rows), f"{len(rows)} cornerness peaks off one line: corrupted or overlapping streaks")
    ends = np.array([subpixel_peak(response, rows[k], cols[k], half_window_px) for k in pair])
    span = ends[1] - ends[0]
    length = np.linalg.norm(span)
    if length < min_separation_px:
        return _failed(len(rows), "the two peaks are too close for a streak")
    ends = ends + np.asarray(origin_xy, dtype=float)
    ends[0] -= bias_px * span / length
    ends[1] += bias_px * span / length
    return Endpoints(True, ends, len(rows))


def along_streak_offsets(measured_xy: ArrayLike, true_xy: ArrayLike) -> NDArray[np.float64]:
    """Outward offsets (px) of measured ends from the true ones, (N, 2) each end's.

    ``measured_xy`` and ``true_xy`` are (N, 2, 2) with the ends paired (same order); positive
    means the measured end lies outside the true streak (too long), negative inside.
    """
    measured = np.asarray(measured_xy, dtype=float)
    truth = np.asarray(true_xy, dtype=float)
    axis = truth[:, 1] - truth[:, 0]
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    first = -np.sum((measured[:, 0] - truth[:, 0]) * axis, axis=1)
    second = np.sum((measured[:, 1] - truth[:, 1]) * axis, axis=1)
    return np.stack([first, second], axis=1)


def calibrate_bias(measured_xy: ArrayLike, reference_xy: ArrayLike | None = None,
                   length_moments_px: ArrayLike | None = None) -> float:
    """Inward endpoint bias (px) to pass as ``bias_px``, from a set of streaks.

    Either against known ends (``reference_xy`` (N, 2, 2), e.g. a simulation of the camera: the
    mean of :func:`along_streak_offsets`, negated), or without truth from each streak's
    moment length (:class:`.streak_detect.StreakRegion`): half the median of
    ``length_moments - measured length``, which works on the flight images themselves
    (seed 001 ch. 6 proposes using the unbiased streak middle the same way).
    """
    measured = np.asarray(measured_xy, dtype=float)
    if reference_xy is not None:
        return float(-np.mean(along_streak_offsets(measured, reference_xy)))
    if length_moments_px is None:
        raise InvalidInputError("calibrate_bias needs reference_xy or length_moments_px")
    lengths = np.linalg.norm(measured[:, 1] - measured[:, 0], axis=1)
    return float(0.5 * np.median(np.asarray(length_moments_px, dtype=float) - lengths))
