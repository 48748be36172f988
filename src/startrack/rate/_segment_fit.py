"""Streak ends by fitting a blurred line segment to the pixels (robust at low per-pixel SNR).

Not in Sease 2013, which uses corner detectors (:mod:`._endpoints`); those need a streak whose
pixels stand well above the noise: on a catalog frame with the faint streaks of a 12-degree
field (a few counts per pixel over a noise of 6) the cornerness map has tens of peaks on the
noise and the ends are lost. A star moving uniformly during the exposure draws a segment from
``p1`` to ``p2`` blurred by its Gaussian PSF of sigma ``s``, and that image is separable along
(t) and across (d) the segment::

    I(t, d) = b + a exp(-d^2 / 2 s^2) [erf((t - t1) / (sqrt(2) s)) - erf((t - t2) / (sqrt(2) s))] / 2

(with ``d`` measured from a parabola of fitted curvature for the arcs of long streaks) so the ends
come from a least-squares fit of (offset across, angle, t1, t2, a, s, b, curvature) to the pixels
near the streak, which uses all the streak's light (the corner detectors use the few pixels
at each end). The fit also says when a region is not one clean streak: a width far from the
PSF's, a poor chi-square (crossing streaks, a curved trail), or an end on the image border
(a star entering or leaving the field during the exposure).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import optimize, special

SIGMA_RANGE_PX = (0.4, 2.5)
"""Fitted blur outside this range: not one star's streak (merged streaks, a cosmic, a blob)."""
MAX_REDUCED_CHI2 = np.inf
"""Largest chi-square per pixel (in units of the background noise variance). None by default:
the photon noise of bright streaks raises it (to ~5 on bright test streaks), so the image's
streaks are compared with each other instead (:func:`.streak_rate.measure_streaks`)."""
BAND_PX = 6.0
"""Pixels farther than this from the streak's moment axis are left out of the fit."""
MAX_EVALUATIONS = 60
"""Model evaluations allowed per fit (with the analytic Jacobian clean streaks converge in 10-20;
a region of merged streaks, which the fit rejects anyway, used to take the default 800 and, with
the dense SVD per step contending for BLAS threads, ~20 s)."""
EDGE_MARGIN_SIGMAS = 3.0
"""An end closer than this many blur sigmas to the image border may be cut by it."""


def segment_image(xs: NDArray, ys: NDArray, centre: NDArray, angle: float, t1: float, t2: float,
                  amplitude: float, sigma: float, offset: float = 0.0, curvature: float = 0.0) -> NDArray[np.float64]:
    """The blurred segment model (module docstring) at pixels (xs, ys) (any matching shapes).

    ``centre`` (2,) is a point of the line, ``angle`` its direction (rad, from +x towards +y),
    ``t1``, ``t2`` the ends' positions along it (px), ``amplitude`` the peak of an infinitely
    long line, ``sigma`` the blur (px), ``offset`` a constant background and ``curvature``
    (1/px) bends the path into the parabola ``d = curvature t^2 / 2`` (the arcs of long streaks).
    """
    u = np.array([np.cos(angle), np.sin(angle)])
    dx, dy = xs - centre[0], ys - centre[1]
    t = dx * u[0] + dy * u[1]
    d = -dx * u[1] + dy * u[0] - 0.5 * curvature * t**2
    scale = np.sqrt(2.0) * sigma
    along = 0.5 * (special.erf((t - t1) / scale) - special.erf((t - t2) / scale))
    return offset + amplitude * np.exp(-0.5 * (d / sigma) ** 2) * along


def model_and_jacobian(p: NDArray, xs: NDArray, ys: NDArray, centroid: NDArray) -> tuple[NDArray, NDArray]:
    """The fitted model (M,) at pixels (xs, ys) (M,) and its analytic Jacobian (M, 8).

    ``p`` = (offset across from ``centroid`` (2,), angle, t1, t2, amplitude, sigma, background,
    curvature), the parameters of :func:`fit_segment`; one pass gives all derivatives, in place
    of the 9 model evaluations of a finite-difference Jacobian.
    """
    offset, angle, t1, t2, amplitude, sigma, _, curvature = p
    u = np.array([np.cos(angle), np.sin(angle)])
    dx, dy = xs - centroid[0] + offset * u[1], ys - centroid[1] - offset * u[0]
    t = dx * u[0] + dy * u[1]
    d0 = -dx * u[1] + dy * u[0]
    d = d0 - 0.5 * curvature * t**2
    scale = np.sqrt(2.0) * sigma
    z1, z2 = (t - t1) / scale, (t - t2) / scale
    e1, e2 = np.exp(-(z1**2)), np.exp(-(z2**2))
    along = 0.5 * (special.erf(z1) - special.erf(z2))
    across = np.exp(-0.5 * (d / sigma) ** 2)
    model = p[6] + amplitude * across * along
    d_across = -amplitude * along * across * d / sigma**2  # dM/dd
    d_along = amplitude * across / np.sqrt(np.pi)  # times dalong/d(..) below
    jac = np.empty((len(t), 8))
    jac[:, 0] = -d_across  # dt/doffset = 0, dd/doffset = -1
    jac[:, 1] = d_across * (-t - curvature * t * (offset + d0)) + d_along * (e1 - e2) / scale * (offset + d0)
    jac[:, 2] = -d_along * e1 / scale
    jac[:, 3] = d_along * e2 / scale
    jac[:, 4] = across * along
    jac[:, 5] = -d_across * d / sigma + d_along * (z2 * e2 - z1 * e1) / sigma
    jac[:, 6] = 1.0
    jac[:, 7] = -0.5 * d_across * t**2
    return model, jac


def line_kernel(length_px: float, angle: float, sigma_px: float = 1.0) -> NDArray[np.float64]:
    """A unit-sum image of a blurred segment of ``length_px`` through the kernel's centre."""
    half = int(np.ceil(0.5 * length_px + 3 * sigma_px))
    ys, xs = np.mgrid[-half:half + 1, -half:half + 1].astype(float)
    kernel = segment_image(xs, ys, np.zeros(2), angle, -0.5 * length_px, 0.5 * length_px, 1.0, sigma_px)
    return kernel / kernel.sum()


@dataclass(frozen=True)
class SegmentFit:
    """The fitted segment of one region, or why it is not a clean streak.

    ``xy`` (2, 2) are the two ends (x, y) in full-image pixels (NaN when not ok), in no time
    order; ``sigma_xy_px`` (2,) the 1-sigma of each end along the streak from the fit's
    covariance; ``blur_px`` the fitted PSF sigma; ``reduced_chi2`` the chi-square per pixel.
    """

    ok: bool
    xy: NDArray[np.float64]
    sigma_xy_px: NDArray[np.float64]
    blur_px: float
    reduced_chi2: float
    reason: str = ""


def _failed(reason: str, blur: float = np.nan, chi2: float = np.nan) -> SegmentFit:
    return SegmentFit(False, np.full((2, 2), np.nan), np.full(2, np.nan), blur, chi2, reason)


def _initial(xs: NDArray, ys: NDArray, values: NDArray, centroid: NDArray, direction: NDArray,
             noise: float) -> NDArray[np.float64]:
    """Start values (offset, angle, t1, t2, a, s, b, curvature) from the bright pixels' extent along the axis."""
    t = (xs - centroid[0]) * direction[0] + (ys - centroid[1]) * direction[1]
    d = -(xs - centroid[0]) * direction[1] + (ys - centroid[1]) * direction[0]
    near = np.abs(d) < 1.5
    bright = near & (values > 2.0 * noise)
    span = t[bright] if np.count_nonzero(bright) >= 2 else t
    inside = near & (t >= span.min()) & (t <= span.max())
    amplitude = max(float(np.median(values[inside])) if inside.any() else noise, noise)
    angle = float(np.arctan2(direction[1], direction[0]))
    return np.array([0.0, angle, span.min(), span.max(), amplitude, 1.0, 0.0, 0.0])


def fit_segment(
    roi: ArrayLike,
    origin_xy: ArrayLike,
    centroid_xy: ArrayLike,
    direction: ArrayLike,
    noise: float,
    *,
    mask: ArrayLike | None = None,
    image_shape: tuple[int, int] | None = None,
    max_reduced_chi2: float = MAX_REDUCED_CHI2,
    band_px: float = BAND_PX,
    sigma_range_px: tuple[float, float] = SIGMA_RANGE_PX,
) -> SegmentFit:
    """Fit the blurred segment to a background-subtracted ROI (h, w) (module docstring).

    ``origin_xy`` is the full-image (x, y) of ``roi[0, 0]``; ``centroid_xy`` and ``direction``
    (unit (x, y)) start the fit (from :class:`.streak_detect.StreakRegion`); ``noise`` is the
    per-pixel noise sigma (image units); ``mask`` (h, w) leaves out pixels (other stars);
    ``image_shape`` (H, W) enables the border check; only pixels within ``band_px`` of the
    starting line are fitted. A region the fit cannot take (a noise that is not positive, a
    model that cannot be evaluated at the start) gives a not-ok result with the reason.
    """
    img = np.asarray(roi, dtype=float)
    use = np.ones(img.shape, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    origin = np.asarray(origin_xy, dtype=float)
    centroid = np.asarray(centroid_xy, dtype=float)
    u = np.asarray(direction, dtype=float)
    gy, gx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    across = np.abs(-(gx + origin[0] - centroid[0]) * u[1] + (gy + origin[1] - centroid[1]) * u[0])
    rows, cols = np.nonzero(use & (across <= band_px))
    xs, ys, values = cols + origin[0], rows + origin[1], img[rows, cols]
    if len(values) < 10:
        return _failed("too few pixels near the streak's line")
    if not (np.isfinite(noise) and noise > 0) or not np.all(np.isfinite(values)):
        return _failed(f"no fit without a positive noise and finite pixels (noise {noise!r})")
    start = _initial(xs, ys, values, centroid, u, noise)
    lower = [-np.inf, -np.inf, -np.inf, -np.inf, 0.0, 0.2, -np.inf, -0.1]
    upper = [np.inf, np.inf, np.inf, np.inf, np.inf, 10.0, np.inf, 0.1]
    try:
        fit = optimize.least_squares(lambda p: (model_and_jacobian(p, xs, ys, centroid)[0] - values) / noise, start,
                                     jac=lambda p: model_and_jacobian(p, xs, ys, centroid)[1] / noise,
                                     bounds=(lower, upper), x_scale="jac", max_nfev=MAX_EVALUATIONS, tr_solver="lsmr")
    except (ValueError, np.linalg.LinAlgError) as exc:  # a start the model cannot evaluate: not a streak
        return _failed(f"the segment fit could not run ({exc})")
    return _judge(fit, centroid, len(values), image_shape, max_reduced_chi2, sigma_range_px)


def _judge(fit, centroid: NDArray, n_pixels: int, image_shape, max_reduced_chi2: float,
           sigma_range_px: tuple[float, float]) -> SegmentFit:
    """Ends, their precision, and the quality checks of a finished fit."""
    offset, angle, t1, t2, _, blur, _, curvature = fit.x
    chi2 = float(2.0 * fit.cost / max(n_pixels - len(fit.x), 1))
    if not fit.success:
        return _failed(f"the segment fit did not converge ({fit.message})", blur, chi2)
    if not sigma_range_px[0] <= blur <= sigma_range_px[1]:
        return _failed(f"fitted blur {blur:.2f} px: not one star's streak", blur, chi2)
    if chi2 > max_reduced_chi2:
        return _failed(f"chi-square per pixel {chi2:.2f}: crossing streaks or not a streak", blur, chi2)
    u = np.array([np.cos(angle), np.sin(angle)])
    centre = centroid + offset * np.array([-u[1], u[0]])
    normal = np.array([-u[1], u[0]])
    ends = np.array([centre + t * u + 0.5 * curvature * t**2 * normal for t in (t1, t2)])
    if image_shape is not None and _near_border(ends, image_shape, EDGE_MARGIN_SIGMAS * blur):
        return _failed("an end at the image border: the star entered or left the field", blur, chi2)
    sigma = _end_sigmas(fit.jac) * np.sqrt(max(chi2, 1.0))  # photon noise above the background's
    return SegmentFit(True, ends, sigma, float(blur), chi2)


def _near_border(ends: NDArray, shape: tuple[int, int], margin: float) -> bool:
    x, y = ends[:, 0], ends[:, 1]
    return bool(np.any((x < margin) | (y < margin) | (x > shape[1] - 1 - margin) | (y > shape[0] - 1 - margin)))


def _end_sigmas(jac: NDArray) -> NDArray[np.float64]:
    """1-sigma of t1 and t2 (px) from the Jacobian of the noise-normalised residuals."""
    try:
        cov = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full(2, np.inf)
    return np.sqrt(np.abs(np.diag(cov)[2:4]))
