"""Streak endpoint detectors and sub-pixel endpoint localisation.

Sease 2013 §3 eqs. 3.1-3.16 (Sease 2013 Eq. 3.1–3.4, Eq. 3.14–3.16). A streak's two ends respond like
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
  inter-pixel approximation between adjacent lines (with the index of eq. 3.12 corrected,
  Sease 2013). The seed's two-resolution candidate search is a speed-up that a single ROI does
  not need, so the cornerness is computed at full resolution on the (lightly smoothed) ROI.

Localisation (eqs. 3.14-3.16): non-maximum suppression (strictly greater than the 8
neighbours) above a fraction of the strongest response, on the streak's own pixels (a ``mask``
leaves out the other streaks that a long diagonal streak's bounding box takes in). The seed
accepts a ROI only with exactly two peaks; here the peaks are told apart by the streak's own
geometry (:func:`streak_path`: a parabola through its bright pixels, which also follows curved
streaks): each end is the strongest peak near an end of the path, peaks along the path between
(false corners on the body: Trajkovic-4 makes them as strong as the ends on diagonal streaks)
are ignored, and a peak off the path (a crossing, a non-star) rejects the ROI. Then the centre of
intensity of the clipped cornerness in a (2N + 1)^2 window, with the coordinate weights eq. 3.15
omits (Sease 2013).

Every Gaussian smoothing pulls the peaks inward along the streak (Sease 2013 p.40): a bias for a
camera and detector, removed by moving both ends outward along the streak. On the pixel grid it
depends on the streak's direction (Trajkovic-4: 1.2 px along the axes, 2.3 px on the diagonals),
so :func:`calibrate_bias_model` fits it as harmonics of the direction (:class:`EndpointBias`);
:func:`calibrate_bias` gives the mean alone.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from ..errors import InvalidInputError, check_choice

CornerDetector = Literal["harris", "min_eigenvalue", "trajkovic4", "trajkovic8"]
"""The corner detectors of :func:`cornerness` (Sease 2013 ch. 3)."""
DETECTORS: tuple[CornerDetector, ...] = get_args(CornerDetector)
"""The names of :data:`CornerDetector`, in its order."""
SEED_HARRIS_K = 0.15
"""Sease 2013's hand-tuned Harris constant (p.24)."""
HARRIS_K = 0.04
"""Our default: with a 1-pixel integration window it gives endpoints about 1.5x more precise
than the seed's 0.15 on our simulated streaks (benchmarks/streak_benchmark.py, docs)."""
INTEGRATION_SIGMA_PX = 1.0
HALF_WINDOW_PX = 2
SUPPORT_FRACTION = 0.25
"""Pixels of the smoothed ROI above this fraction of its maximum outline the streak."""
END_RADIUS_PX = 5.0
"""A streak's end is the strongest cornerness peak within this distance of an end of its bright
pixels (measured: the right peak lies within 3.6 px, body and noise peaks farther)."""


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
    """Harris cornerness ``det A - k (tr A)^2`` (Sease 2013 eq. 3.8)."""
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


def check_detector(detector: str) -> CornerDetector:
    """``detector`` as a :data:`CornerDetector`; an InvalidInputError naming the valid ones if it is not one."""
    return check_choice(detector, DETECTORS, "detector")


def cornerness(roi: ArrayLike, detector: CornerDetector = "harris", **params) -> NDArray[np.float64]:
    """Cornerness map of a background-subtracted ROI for one of :data:`DETECTORS`."""
    detector = check_detector(detector)
    img = np.asarray(roi, dtype=float)
    if detector == "harris":
        return harris_response(img, **params)
    if detector == "min_eigenvalue":
        return min_eigenvalue_response(img, **params)
    return trajkovic_response(img, neighbours=int(detector[-1]), **params)  # trajkovic4 or trajkovic8


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


@dataclass(frozen=True)
class StreakPath:
    """The centre line of a streak's bright pixels: a parabola ``d = c0 + c1 t + c2 t^2`` across
    the streak's principal axis, over ``t_range`` along it (all in ROI pixels).

    ``centre`` (2,) and ``axis`` (2,) (unit) are the (x, y) origin and direction of t; ``coeffs``
    (3,) are c0, c1, c2. The ends of the path are where the bright pixels end: within a few
    pixels of the streak's ends, which is how the cornerness peaks are told apart.
    """

    centre: NDArray[np.float64]
    axis: NDArray[np.float64]
    coeffs: NDArray[np.float64]
    t_range: NDArray[np.float64]

    def _frame(self, points: ArrayLike) -> tuple[NDArray, NDArray]:
        rel = np.asarray(points, dtype=float) - self.centre
        return rel @ self.axis, rel @ np.array([-self.axis[1], self.axis[0]])

    def offsets(self, points: ArrayLike) -> NDArray[np.float64]:
        """Distance across the path (px) of points (N, 2) (x, y)."""
        t, d = self._frame(points)
        return np.abs(d - np.polyval(self.coeffs[::-1], t))

    def ends(self) -> NDArray[np.float64]:
        """The path's two ends (2, 2) (x, y)."""
        t = self.t_range
        d = np.polyval(self.coeffs[::-1], t)
        return self.centre + t[:, None] * self.axis + d[:, None] * np.array([-self.axis[1], self.axis[0]])


def streak_path(roi: ArrayLike, mask: ArrayLike | None = None, fraction: float = SUPPORT_FRACTION,
                smooth_sigma_px: float = 1.0) -> StreakPath | None:
    """The path of the streak in a background-subtracted ROI (h, w), from its bright pixels.

    The ROI is smoothed, the pixels above ``fraction`` of its maximum (inside ``mask``) are
    labelled and the brightest component (largest sum) is the streak; its principal axis and a
    weighted parabola across it give the path (curved streaks: Sease 2013 p.35). None when the
    ROI has no positive pixel.
    """
    img = ndimage.gaussian_filter(np.asarray(roi, dtype=float), smooth_sigma_px, mode="nearest")
    if mask is not None:
        img = np.where(mask, img, 0.0)
    top = float(np.max(img))
    if top <= 0:
        return None
    labels, count = ndimage.label(img > fraction * top)
    keep = 1 + int(np.argmax(ndimage.sum(img, labels, np.arange(1, count + 1))))
    ys, xs = np.nonzero(labels == keep)
    w = img[ys, xs]
    points = np.column_stack([xs, ys]).astype(float)
    centre = w @ points / w.sum()
    rel = points - centre
    _, vectors = np.linalg.eigh((rel * w[:, None]).T @ rel)
    axis = vectors[:, 1]
    t, d = rel @ axis, rel @ np.array([-axis[1], axis[0]])
    degree = 2 if np.ptp(t) > 4.0 else 0
    coeffs = np.zeros(3)
    coeffs[: degree + 1] = np.polynomial.polynomial.polyfit(t, d, degree, w=np.sqrt(w))
    return StreakPath(centre, axis, coeffs, np.array([t.min(), t.max()]))


def _end_peaks(points: NDArray, strength: NDArray, path: StreakPath, end_radius_px: float) -> list[int] | None:
    """Index of the strongest peak within ``end_radius_px`` of each end of the path (None if
    an end has none, or both ends chose the same peak)."""
    chosen = []
    for end in path.ends():
        near = np.flatnonzero(np.linalg.norm(points - end, axis=1) <= end_radius_px)
        if len(near) == 0:
            return None
        chosen.append(int(near[np.argmax(strength[near])]))
    return chosen if chosen[0] != chosen[1] else None


def locate_endpoints(
    roi: ArrayLike,
    origin_xy: ArrayLike = (0.0, 0.0),
    detector: CornerDetector = "harris",
    *,
    mask: ArrayLike | None = None,
    half_window_px: int = HALF_WINDOW_PX,
    min_fraction: float = 0.1,
    line_tolerance_px: float = 3.0,
    end_radius_px: float = END_RADIUS_PX,
    bias_px: float | EndpointBias = 0.0,
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
    detector : CornerDetector
        One of :data:`DETECTORS` (another name is refused with the valid ones); ``params`` go
        to it (k, integration_sigma_px, ...).
    mask : array_like of bool, shape (h, w), optional
        Pixels that belong to this streak or the background; False on other streaks that the
        ROI's bounding box takes in (long diagonal streaks), whose corners and light are then
        ignored. Default: all pixels.
    half_window_px : int
        N of the (2N + 1)^2 sub-pixel window.
    min_fraction : float
        Peaks below this fraction of the strongest are ignored.
    line_tolerance_px : float
        Every peak must lie within this distance of the streak's path (:func:`streak_path`, a
        parabola through its bright pixels, so curved streaks pass); a peak off it (a crossing,
        a non-star) rejects the ROI, as the seed rejects every ROI with more than two peaks.
        Peaks on the path between the ends (false corners along the body) are allowed.
    end_radius_px : float
        Each end is the strongest peak within this distance of an end of the path.
    bias_px : float or EndpointBias
        Calibrated inward bias (px, or as a function of the streak's direction); both ends are
        moved outward by it along the streak.
    min_separation_px : float
        Two peaks closer than this are not a streak (a point star).

    Returns
    -------
    Endpoints
        ``ok`` False with a reason for fewer than two peaks, peaks off the path, an end of the
        path without a peak, or peaks too close together.
    """
    detector = check_detector(detector)
    img = np.asarray(roi, dtype=float)
    use = np.ones(img.shape, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    response = np.where(use, cornerness(img, detector, **params), 0.0)
    rows, cols = local_maxima(response, min_fraction)
    path = streak_path(img, use)
    if len(rows) < 2 or path is None:
        return _failed(len(rows), "fewer than two cornerness peaks")
    points = np.column_stack([cols, rows]).astype(float)
    if np.max(path.offsets(points)) > line_tolerance_px:
        return _failed(len(rows), f"{len(rows)} cornerness peaks off the streak: corrupted or overlapping streaks")
    pair = _end_peaks(points, response[rows, cols], path, end_radius_px)
    if pair is None:
        return _failed(len(rows), "no separate cornerness peak at each end of the streak")
    ends = np.array([subpixel_peak(response, rows[k], cols[k], half_window_px) for k in pair])
    span = ends[1] - ends[0]
    length = np.linalg.norm(span)
    if length < min_separation_px:
        return _failed(len(rows), "the two peaks are too close for a streak")
    shift = bias_px.at(span) if isinstance(bias_px, EndpointBias) else bias_px
    ends = ends + np.asarray(origin_xy, dtype=float) + np.outer([-shift, shift], span / length)
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


HARMONICS = (4,)
"""Orders of the direction harmonics of :class:`EndpointBias`: the pixel grid has the symmetry
of a square, so a detector's bias repeats every 90 degrees of streak direction (a cos 8a term measured below
0.1 px)."""


@dataclass(frozen=True)
class EndpointBias:
    """Inward endpoint bias (px) as a function of the streak's direction angle a:
    ``c0 + sum_k (c_k cos(n_k a) + s_k sin(n_k a))`` over ``harmonics`` n_k.

    The corner detectors work on the pixel grid, so their inward pull depends on the streak's
    direction: measured, Trajkovic-4 pulls an end in by 1.2 px along the grid axes and 2.3 px
    on the diagonals; Harris and minimum eigenvalue by nearly the same at every direction.
    ``coeffs`` holds c0, then (c_k, s_k) for each harmonic. ``float()`` gives the mean c0.
    """

    coeffs: NDArray[np.float64]
    harmonics: tuple[int, ...] = HARMONICS

    def at(self, direction_xy: ArrayLike) -> float:
        """The bias (px) for a streak along ``direction_xy`` (2,) (x, y), either sense."""
        d = np.asarray(direction_xy, dtype=float)
        return float(_harmonic_design(np.arctan2(d[..., 1], d[..., 0]), self.harmonics) @ self.coeffs)

    def __float__(self) -> float:
        return float(self.coeffs[0])


def _harmonic_design(angles: ArrayLike, harmonics: tuple[int, ...]) -> NDArray[np.float64]:
    a = np.atleast_1d(np.asarray(angles, dtype=float))
    columns = [np.ones_like(a)] + [f(n * a) for n in harmonics for f in (np.cos, np.sin)]
    return np.squeeze(np.stack(columns, axis=-1))


def _inward_offsets(measured: NDArray, reference_xy, length_moments_px) -> tuple[NDArray, NDArray]:
    """Per-end inward offsets (M,) and the direction angles (M,) of their streaks."""
    angles = np.arctan2(*(measured[:, 1] - measured[:, 0]).T[::-1])
    if reference_xy is not None:
        return -along_streak_offsets(measured, reference_xy).ravel(), np.repeat(angles, 2)
    if length_moments_px is None:
        raise InvalidInputError("calibrate_bias needs reference_xy or length_moments_px")
    lengths = np.linalg.norm(measured[:, 1] - measured[:, 0], axis=1)
    return 0.5 * (np.asarray(length_moments_px, dtype=float) - lengths), angles


def calibrate_bias_model(measured_xy: ArrayLike, reference_xy: ArrayLike | None = None,
                         length_moments_px: ArrayLike | None = None,
                         harmonics: tuple[int, ...] = HARMONICS) -> EndpointBias:
    """The direction-dependent inward bias (:class:`EndpointBias`) from a set of streaks.

    Same inputs as :func:`calibrate_bias` (ends (N, 2, 2) measured with ``bias_px=0``), which
    should cover the directions: a least-squares fit of the harmonics to each end's inward
    offset. Harmonics the directions do not fix (all streaks nearly parallel) are left at zero.
    """
    offsets, angles = _inward_offsets(np.asarray(measured_xy, dtype=float), reference_xy, length_moments_px)
    design = _harmonic_design(angles, harmonics).reshape(len(offsets), -1)
    singular = np.linalg.svd(design / np.sqrt(len(offsets)), compute_uv=False)
    if len(offsets) < 4 * design.shape[1] or singular[-1] < 0.2:
        mean = np.mean(offsets) if reference_xy is not None else np.median(offsets)
        return EndpointBias(np.r_[mean, np.zeros(2 * len(harmonics))], harmonics)
    coeffs, *_ = np.linalg.lstsq(design, offsets, rcond=None)
    return EndpointBias(coeffs, harmonics)


def calibrate_bias(measured_xy: ArrayLike, reference_xy: ArrayLike | None = None,
                   length_moments_px: ArrayLike | None = None) -> float:
    """Inward endpoint bias (px) to pass as ``bias_px``, from a set of streaks.

    Either against known ends (``reference_xy`` (N, 2, 2), e.g. a simulation of the camera: the
    mean of :func:`along_streak_offsets`, negated), or without truth from each streak's
    moment length (:class:`.streak_detect.StreakRegion`): half the median of
    ``length_moments - measured length``, which works on the flight images themselves
    (Sease 2013 ch. 6 proposes using the unbiased streak middle the same way).
    """
    measured = np.asarray(measured_xy, dtype=float)
    offsets, _ = _inward_offsets(measured, reference_xy, length_moments_px)
    return float(np.mean(offsets) if reference_xy is not None else np.median(offsets))
