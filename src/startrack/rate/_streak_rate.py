"""The streaked-image chain of Sease 2013: streaks -> endpoints -> groups -> rate (and attitudes).

Sease 2013 §3-4 (Sease 2013 Ch.3–4). :func:`measure_streaks` finds the streaks
(:mod:`._streak_detect`), locates both ends of each (by default a blurred-segment fit,
:mod:`._segment_fit`, which works on faint catalog streaks; or the seed's corner detectors,
:mod:`._endpoints`) and groups them into the two exposure times (:mod:`._grouping`, then the
rotation most streaks agree with, :func:`.catalog_free.consensus`). Then either

- :func:`streak_rate` (Sease 2013 ch. 4, no catalog): OLAE between the groups with outlier
  rejection (:mod:`._catalog_free`), a trust check (:mod:`._trust`: no rate when too few streaks
  agree or its uncertainty exceeds 5 %) and the three RSO indicators (:mod:`._rso`); or
- :func:`streak_attitudes` (Sease 2013 ch. 3): identify the group-A ends lost-in-space against the
  catalog, reuse the same identities for the group-B ends (they are the same stars), solve the
  attitude at both ends (ESOQ2, as the seed) and take the rate between them
  (:mod:`._from_attitudes`).

Time order: one image tells which ends are simultaneous, not which set came first. With a prior
rate (a gyro, the previous frame, the commanded slew) the order whose rate agrees with it is
chosen (``time_order_known``); without one, group A is taken as the start.

:func:`choose_mode` is the automatic switch between point-star and streak processing: streaks
shorter than about 10 % of the field of view approach the point-star regime where the corner
detectors fail (Sease 2013 p.37-38), so the point-star solver is used there.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Final, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage
from scipy.spatial.transform import Rotation

from ..attitude import WahbaMethod, solve_wahba
from ..camera import Camera
from ..errors import (
    InvalidInputError,
    as_float_array,
    check_choice,
    check_instance,
    checked_count,
    checked_number,
    require,
)
from ..results import AttitudeSolution, Status
from ._catalog_free import CatalogFreeRate, catalog_free_rate, consensus, regroup
from ._endpoints import CornerDetector, EndpointBias, locate_endpoints
from ._estimate import RateEstimate, checked_exposure, checked_prior, failed
from ._from_attitudes import rate_between
from ._grouping import CentreOfRotation, centre_of_rotation, group_endpoints
from ._rso import RsoIndicators, rso_indicators
from ._segment_fit import BAND_PX, fit_segment
from ._streak_detect import StreakRegion, find_streaks, median_length_px
from ._streak_find import ROUNDING_SIGMA
from ._trust import MAX_RELATIVE_UNCERTAINTY, consensus_tolerance_px, consistency, rate_covariance

MIN_STREAK_FRACTION = 0.10
"""Streaks shorter than this fraction of the image width are processed as point stars."""


LENGTH_TOLERANCE = (3.0, 0.05)
"""Largest difference between a streak's end separation and its moment length: 3 px + 5 %.
Measured good ends differ by -1.5 to +0.5 px (Harris, minimum eigenvalue) and up to -3 px
(Trajkovic) before the bias correction, on 10 % and 50 % streaks (docs/attitude_and_rate.md)."""


def length_mismatch(ends_xy: ArrayLike, length_moments_px: float,
                    tolerance: tuple[float, float] = LENGTH_TOLERANCE) -> bool:
    """True when the ends (2, 2) are farther from the moment length than ``tolerance`` allows.

    The moment length (:class:`.streak_detect.StreakRegion`) does not depend on the corner
    detector, so it catches an end placed on a false corner along the body or beyond the streak.
    """
    ends = np.asarray(ends_xy, dtype=float)
    separation = float(np.linalg.norm(ends[1] - ends[0]))
    return abs(separation - length_moments_px) > tolerance[0] + tolerance[1] * length_moments_px


SEGMENT: Final = "segment"
"""The blurred-segment fit (:mod:`._segment_fit`): the default endpoint method."""
EndpointMethod = Literal["segment", CornerDetector]
"""How :func:`measure_streaks` finds a streak's ends: the segment fit or a corner detector."""
METHODS: tuple[EndpointMethod, ...] = get_args(EndpointMethod)
"""The names of :data:`EndpointMethod`, in its order."""


def check_endpoint_method(detector: str) -> EndpointMethod:
    """``detector`` as an :data:`EndpointMethod`; an InvalidInputError naming the valid ones if it is not one."""
    return check_choice(detector, METHODS, "detector")
SEGMENT_FIND_OPTIONS = {"line_filter_px": 25.0, "threshold_sigma": 5.0, "margin_px": 6}
"""Segmentation for the segment fit: a 25-px line filter at 5 sigma keeps faint streaks whole."""
MAX_END_SIGMA_PX = 2.0
"""Segment fits whose ends are less precise than this (1 sigma along the streak) are dropped."""
BLUR_TOLERANCE = 0.35
"""Largest relative difference of a streak's fitted blur from the median (one PSF for all)."""
CHI2_FACTOR = 3.0
"""Largest chi-square per pixel of a segment fit relative to the median (crossing streaks)."""
NOISE_FLOOR = ROUNDING_SIGMA
"""Least per-pixel noise (counts) the segment fit assumes: the quantisation noise of one count, for
images whose background has no measurable noise (simulated without noise, or clipped at zero)."""


@dataclass(frozen=True)
class StreakMeasurement:
    """Streaks with two clean ends, grouped by exposure time.

    ``ends_a`` and ``ends_b`` (N, 2) are the pixel ends of the N kept streaks (``regions``);
    ``rejected`` counts the regions without two clean ends; ``end_sigma_px`` (N,) is each end's
    1-sigma precision (px; the segment fit's, or a nominal 0.3 px for the corner detectors);
    ``agree`` (N,) marks the streaks consistent with one common rotation (all True when it was
    not checked: no camera, or a corner detector).
    """

    status: Status
    reason: str
    regions: list[StreakRegion]
    ends_a: NDArray[np.float64]
    ends_b: NDArray[np.float64]
    cor: CentreOfRotation | None
    rejected: int
    end_sigma_px: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    agree: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))


def _corner_ends(img, found, detector, bias_px, min_length_px, length_tolerance, endpoint_options):
    """Regions and ends (N, 2, 2) located by a corner detector, checked against the moment length."""
    kept, ends = [], []
    for region in found.regions:
        if region.length_moments_px < min_length_px:
            continue
        roi = img[region.rows, region.cols] - found.background
        result = locate_endpoints(roi, region.origin_xy, detector, mask=~_other_streaks(region, found),
                                  bias_px=bias_px, **(endpoint_options or {}))
        if result.ok and not length_mismatch(result.xy, region.length_moments_px, length_tolerance):
            kept.append(region)
            ends.append(result.xy)
    return kept, ends, np.full(len(kept), 0.3)


def _segment_ends(img, found, min_length_px):
    """Regions, ends (N, 2, 2) and end sigmas (N,) from the segment fit, with a common blur."""
    fits = []
    noise = max(found.noise, NOISE_FLOOR)
    for region in found.regions:
        result = fit_segment(img[region.rows, region.cols] - found.background, region.origin_xy,
                             region.centroid_xy, region.direction, noise, mask=~_other_streaks(region, found),
                             image_shape=img.shape,
                             band_px=BAND_PX + 2.0 * region.width_px)
        length = np.linalg.norm(result.xy[1] - result.xy[0])
        if result.ok and length >= min_length_px and np.max(result.sigma_xy_px) <= MAX_END_SIGMA_PX:
            fits.append((region, result))
    if not fits:
        return [], [], np.zeros(0)
    blur = np.array([f.blur_px for _, f in fits])
    chi2 = np.array([f.reduced_chi2 for _, f in fits])
    common = (np.abs(blur / np.median(blur) - 1.0) <= BLUR_TOLERANCE) & (chi2 <= CHI2_FACTOR * np.median(chi2))
    fits = [f for f, ok in zip(fits, common, strict=True) if ok]
    return [r for r, _ in fits], [f.xy for _, f in fits], np.array([np.max(f.sigma_xy_px) for _, f in fits])


def _other_streaks(region: StreakRegion, found) -> NDArray[np.bool_]:
    """Pixels of a region's ROI on (or within 3 px of) other labelled blobs, which a long diagonal
    streak's bounding box takes in."""
    labels = found.labels[region.rows, region.cols]
    return ndimage.binary_dilation((labels > 0) & (labels != _label_of(region, found.labels)), iterations=3)


def _label_of(region: StreakRegion, labels: NDArray) -> int:
    """The label of a region: the most common non-zero label inside its ROI's unpadded core."""
    values = labels[region.rows, region.cols]
    values = values[values > 0]
    return int(np.bincount(values).argmax()) if values.size else 0


def measure_streaks(
    image: ArrayLike,
    camera: Camera | None = None,
    *,
    detector: str = SEGMENT,
    bias_px: float | EndpointBias = 0.0,
    min_length_px: float = 6.0,
    length_tolerance: tuple[float, float] = LENGTH_TOLERANCE,
    find_options: dict | None = None,
    endpoint_options: dict | None = None,
) -> StreakMeasurement:
    """Find the streaks of an image, locate and group their ends (module docstring).

    ``detector`` is an :data:`EndpointMethod` (another name is refused with the valid ones):
    ``"segment"`` (the blurred-segment fit, :mod:`._segment_fit`, on a line-filtered
    segmentation) or a corner detector of :mod:`._endpoints`. ``find_options`` go
    to :func:`.streak_detect.find_streaks`, ``endpoint_options`` to
    :func:`.endpoints.locate_endpoints` (with ``detector`` and ``bias_px``). With a corner
    detector, a streak whose (bias-corrected) end separation differs from its moment length by
    more than ``length_tolerance`` = (px, fraction of the length) is rejected: one end was put
    on a false corner (:func:`length_mismatch`). With a ``camera``,
    the centre-of-rotation grouping is checked against the common rotation and streaks whose
    ends fit it better the other way round are swapped (:func:`.catalog_free.regroup`); with
    the segment fit, the largest set of streaks agreeing on one rotation is found first
    (:func:`.catalog_free.consensus`, marked in ``agree``). Fewer than two streaks give status
    TOO_FEW_STARS.
    """
    detector = check_endpoint_method(detector)
    _check_bias(bias_px)
    img = as_float_array(image, "image")
    defaults = SEGMENT_FIND_OPTIONS if detector == SEGMENT else {}
    found = find_streaks(img, **(defaults | (find_options or {})))
    if detector == SEGMENT:
        kept, ends, sigmas = _segment_ends(img, found, min_length_px)
    else:
        kept, ends, sigmas = _corner_ends(img, found, detector, bias_px, min_length_px, length_tolerance,
                                          endpoint_options)
    rejected = len(found.regions) - len(kept)
    if len(kept) < 2:
        empty = np.zeros((0, 2))
        return StreakMeasurement(Status.TOO_FEW_STARS, f"{len(kept)} streaks with two clean ends (2 needed)",
                                 kept, empty, empty, None, rejected)
    ends = np.array(ends)
    # A centre farther than ~2 focal lengths (spin axis > 63 deg from the boresight) is too
    # poorly fixed by nearly parallel bisectors: use the parallel forms (Sease 2013's trigger).
    far = 1e5 if camera is None else 2.0 * camera.fx
    cor = centre_of_rotation(ends[:, 0], ends[:, 1], max_distance_px=far)
    agree = np.ones(len(kept), dtype=bool)
    if camera is None or len(kept) < 3:
        group_a, group_b, _ = group_endpoints(ends[:, 0], ends[:, 1], cor)
    elif detector == SEGMENT:
        group_a, group_b, agree = _consensus_groups(ends, cor, sigmas, camera)
    else:
        group_a, group_b = _checked_groups(ends, cor, camera)
    return StreakMeasurement(Status.OK, "", kept, group_a, group_b, cor, rejected, sigmas, agree)


def _consensus_groups(ends: NDArray, cor: CentreOfRotation, sigmas: NDArray, camera: Camera):
    """Groups by the centre of rotation, corrected by the consensus rotation; agreeing streaks."""
    group_a, group_b, _ = group_endpoints(ends[:, 0], ends[:, 1], cor)
    va = camera.pixel_to_vector(group_a[:, 0], group_a[:, 1])
    vb = camera.pixel_to_vector(group_b[:, 0], group_b[:, 1])
    found = consensus(va, vb, consensus_tolerance_px(sigmas) / camera.fx)
    swap = found.swap[:, None]
    return np.where(swap, group_b, group_a), np.where(swap, group_a, group_b), found.used


def _checked_groups(ends: NDArray, cor: CentreOfRotation, camera: Camera) -> tuple[NDArray, NDArray]:
    """The grouping (by the centre, or by the dominant direction) that best fits one rotation.

    Each candidate is corrected streak by streak (:func:`.catalog_free.regroup`); the one with
    the smaller median OLAE residual wins.
    """
    best: tuple[NDArray, NDArray] | None = None
    best_cost = np.inf
    for as_parallel in (False, True):
        if cor.parallel and not as_parallel:
            continue
        group_a, group_b, _ = group_endpoints(ends[:, 0], ends[:, 1], cor, as_parallel=as_parallel)
        va = camera.pixel_to_vector(group_a[:, 0], group_a[:, 1])
        vb = camera.pixel_to_vector(group_b[:, 0], group_b[:, 1])
        swap = regroup(va, vb)
        va, vb = np.where(swap[:, None], vb, va), np.where(swap[:, None], va, vb)
        cost = float(np.median(catalog_free_rate(va, vb, 1.0, floor_rad=1e-9).residuals))
        if best is None or cost < best_cost:  # (the first kept when every cost is NaN)
            group_a, group_b = np.where(swap[:, None], group_b, group_a), np.where(swap[:, None], group_a, group_b)
            best, best_cost = (group_a, group_b), cost
    return require(best, "a grouping of the streak ends")


@dataclass(frozen=True)
class StreakRate:
    """Catalog-free rate of a streaked image (Sease 2013 ch. 4), with the RSO indicators.

    ``rate`` is ``omega`` from the start set to the end set (camera frame, rad/s; ``rate.used``
    marks the streaks kept); ``vectors_start`` / ``vectors_end`` (N, 3) are the camera vectors of
    the ends in that order; ``residuals`` the OLAE residual per streak; ``rso`` the indicators.
    """

    rate: RateEstimate
    measurement: StreakMeasurement
    vectors_start: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    vectors_end: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 3)))
    residuals: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    rso: RsoIndicators | None = None
    time_order_known: bool = False


def _check_bias(bias_px: float | EndpointBias) -> float | EndpointBias:
    """``bias_px`` if it is a finite number (px) or an :class:`EndpointBias` with finite
    coefficients; else an InvalidInputError saying so."""
    if isinstance(bias_px, EndpointBias):
        if not np.all(np.isfinite(bias_px.coeffs)):
            raise InvalidInputError("bias_px must have finite coefficients (an EndpointBias from calibrate_bias_model)")
        return bias_px
    return checked_number(bias_px, "bias_px (pixels, or an EndpointBias)")


def _check_rate_inputs(camera: Camera, exposure_s: float, prior: ArrayLike | None, k_sigma: float,
                       endpoint_sigma_px, measurement: StreakMeasurement | None) -> None:
    """Refuse a camera or measurement of another type, an exposure outside the range of
    :func:`._estimate.checked_exposure`, a prior rate that is not a finite vector (3,), and
    non-positive thresholds."""
    check_instance(camera, Camera, "camera")
    if measurement is not None:
        check_instance(measurement, StreakMeasurement, "measurement")
    checked_exposure(exposure_s)
    checked_prior(prior)
    checked_number(k_sigma, "k_sigma", low=0.0, above_low=True)
    if endpoint_sigma_px is not None:
        checked_number(endpoint_sigma_px, "endpoint_sigma_px (or None)", low=0.0, above_low=True)


def _ordered(omega: NDArray, prior: ArrayLike | None) -> tuple[bool, bool]:
    """(swap the groups?, order known?) from the A -> B rate and an optional prior rate (a zero
    prior, as a tracker at rest passes, orders nothing)."""
    if prior is None or not np.any(prior):
        return False, False
    return bool(np.dot(omega, np.asarray(prior, dtype=float)) < 0), True


def _swapped(estimate: RateEstimate) -> RateEstimate:
    return RateEstimate(estimate.status, estimate.reason, -estimate.omega_rad_s, estimate.covariance_rad2_s2,
                        estimate.method, estimate.used)


def streak_rate(
    image: ArrayLike,
    camera: Camera,
    exposure_s: float,
    *,
    detector: EndpointMethod = SEGMENT,
    bias_px: float | EndpointBias = 0.0,
    prior_omega_rad_s: ArrayLike | None = None,
    k_sigma: float = 2.5,
    endpoint_sigma_px: float | None = None,
    measurement: StreakMeasurement | None = None,
) -> StreakRate:
    """Catalog-free rate and RSO candidates of one streaked image (module docstring).

    Parameters
    ----------
    image : array_like, shape (H, W)
        The streaked image (counts).
    camera : Camera
        The calibrated camera (pixel -> vector).
    exposure_s : float
        Exposure time, seconds (the time between the two ends of every streak).
    detector, bias_px : EndpointMethod, float
        Endpoint detector and its calibrated bias (:mod:`._endpoints`).
    prior_omega_rad_s : array_like, shape (3,), optional
        A rough rate of the right sign, to order the two ends in time (zero: the order is not
        known, as without one).
    k_sigma, endpoint_sigma_px : float
        Outlier threshold and the endpoint precision (px) that sets the floors of the OLAE
        rejection and of the RSO indicators; None takes the measurement's median end precision
        for the rejection and each streak's own for the indicators (:func:`.rso.rso_indicators`,
        which also marks the streaks cut by the image border).
    measurement : StreakMeasurement, optional
        Reuse an earlier :func:`measure_streaks` of this image.
    """
    detector = check_endpoint_method(detector)
    _check_rate_inputs(camera, exposure_s, prior_omega_rad_s, k_sigma, endpoint_sigma_px, measurement)
    meas = measurement or measure_streaks(image, camera, detector=detector, bias_px=bias_px)
    if meas.status is not Status.OK:
        return StreakRate(failed(meas.status, meas.reason, "catalog-free OLAE"), meas)
    va = camera.pixel_to_vector(meas.ends_a[:, 0], meas.ends_a[:, 1])
    vb = camera.pixel_to_vector(meas.ends_b[:, 0], meas.ends_b[:, 1])
    pixel_angle = 1.0 / camera.fx
    explicit_sigma = endpoint_sigma_px
    if endpoint_sigma_px is None:
        endpoint_sigma_px = float(np.median(meas.end_sigma_px)) if len(meas.end_sigma_px) else 0.3
    floor = 2 * np.sqrt(2) * endpoint_sigma_px * pixel_angle
    agree = meas.agree if len(meas.agree) == len(va) else None
    fit = catalog_free_rate(va, vb, exposure_s, k_sigma=k_sigma, floor_rad=floor, initial_used=agree)
    fit = _checked(fit, meas, camera, va + vb, exposure_s)
    per_streak = explicit_sigma is None and len(meas.end_sigma_px) == len(va)
    rso = rso_indicators(meas.ends_a, meas.ends_b, camera, fit.residuals, k_sigma=k_sigma,
                         endpoint_sigma_px=meas.end_sigma_px if per_streak else endpoint_sigma_px)
    swap, known = _ordered(fit.estimate.omega_rad_s, prior_omega_rad_s)
    if swap:
        return StreakRate(_swapped(fit.estimate), meas, vb, va, fit.residuals, rso, known)
    return StreakRate(fit.estimate, meas, va, vb, fit.residuals, rso, known)


def _checked(fit: CatalogFreeRate, meas: StreakMeasurement, camera: Camera, vectors: NDArray,
             exposure_s: float) -> CatalogFreeRate:
    """The fit with its covariance, or a not-OK one saying why its streaks do not support it
    (:func:`consistency`, and a 3-sigma uncertainty above :data:`MAX_RELATIVE_UNCERTAINTY`).

    The covariance of :func:`rate_covariance` is scaled up by the Birge ratio (rms of the OLAE
    residuals over their expected size) when the streaks scatter more than their fits claim."""
    est = fit.estimate
    if not est.ok:
        return fit
    status, reason = consistency(require(est.used, "the streaks used"), fit.residuals * camera.fx, meas.end_sigma_px)
    cov = None
    if status is Status.OK and len(meas.end_sigma_px) == len(vectors):
        sigma = meas.end_sigma_px[est.used]
        birge = np.sqrt(np.mean((fit.residuals[est.used] * camera.fx / (np.sqrt(2.0) * sigma)) ** 2))
        cov = rate_covariance(vectors[est.used], sigma, camera.fx, exposure_s) * max(birge, 1.0) ** 2
        relative = 3.0 * np.sqrt(np.trace(cov)) / max(np.linalg.norm(est.omega_rad_s), 1e-12)
        if relative > MAX_RELATIVE_UNCERTAINTY:
            limit = 100 * MAX_RELATIVE_UNCERTAINTY
            status, reason = Status.DEGENERATE, (f"rate uncertain by {100 * relative:.1f} % (3 sigma, > {limit:.0f} %):"
                                                 " too few or too imprecise streaks")
    if status is Status.OK:
        return CatalogFreeRate(RateEstimate(Status.OK, "", est.omega_rad_s, cov, est.method, est.used),
                               fit.residuals, fit.gibbs)
    return CatalogFreeRate(RateEstimate(status, reason, np.full(3, np.nan), cov, est.method, est.used),
                           fit.residuals, fit.gibbs)


@dataclass(frozen=True)
class StreakAttitudes:
    """Attitudes at the two ends of the exposure and the rate between (Sease 2013 ch. 3)."""

    status: Status
    reason: str
    rot_start: Rotation | None
    rot_end: Rotation | None
    rate: RateEstimate
    solution: AttitudeSolution | None
    time_order_known: bool


def attitudes_from_matches(
    vectors_a: ArrayLike, vectors_b: ArrayLike, catalog_icrs: ArrayLike, *, method: WahbaMethod = "esoq2"
) -> tuple[Rotation, Rotation]:
    """Attitudes (rot_cam_from_icrs) of both ends from the same identified stars (N, 3) each."""
    rot_a = solve_wahba(vectors_a, catalog_icrs, method=method)
    rot_b = solve_wahba(vectors_b, catalog_icrs, method=method)
    if not (rot_a.ok and rot_b.ok):
        raise InvalidInputError("need at least two non-parallel identified streaks")
    return rot_a.rotation, rot_b.rotation


def streak_attitudes(
    measurement: StreakMeasurement,
    camera: Camera,
    exposure_s: float,
    *,
    prior_omega_rad_s: ArrayLike | None = None,
    epoch=None,
) -> StreakAttitudes:
    """Identify the group-A ends lost-in-space and solve the attitude at both ends.

    Uses :func:`startrack.solve_stars` with the camera on the group-A ends (brightest streaks
    first), then the matched catalog stars for both groups (:func:`attitudes_from_matches`).
    """
    from ..solve import solve_stars  # deferred: the solve pipeline imports much more

    if measurement.status is not Status.OK:
        return StreakAttitudes(measurement.status, measurement.reason, None, None,
                               failed(measurement.status, measurement.reason, "attitudes"), None, False)
    ends_a, ends_b = measurement.ends_a, measurement.ends_b
    solution = solve_stars(ends_a[:, 0], ends_a[:, 1], camera=camera, epoch=epoch)
    if not solution.solved or len(solution.matches) < 2:
        return StreakAttitudes(solution.status, solution.reason, None, None,
                               failed(solution.status, solution.reason, "attitudes"), solution, False)
    index = solution.matches.det_index
    va = camera.pixel_to_vector(ends_a[index, 0], ends_a[index, 1])
    vb = camera.pixel_to_vector(ends_b[index, 0], ends_b[index, 1])
    rot_a, rot_b = attitudes_from_matches(va, vb, solution.matches.cat_vectors)
    omega = rate_between(rot_a, rot_b, exposure_s)
    swap, known = _ordered(omega, prior_omega_rad_s)
    if swap:
        rot_a, rot_b, omega = rot_b, rot_a, -omega
    rate = RateEstimate(Status.OK, omega_rad_s=omega, method="attitudes at both streak ends")
    return StreakAttitudes(Status.OK, "", rot_a, rot_b, rate, solution, known)


@dataclass(frozen=True)
class ModeDecision:
    """``mode`` "streak" or "point", the median streak length as a fraction of the width, why."""

    mode: str
    length_fraction: float
    reason: str


def choose_mode(image: ArrayLike, *, min_streak_fraction: float = MIN_STREAK_FRACTION,
                brightest: int = 20) -> ModeDecision:
    """Point-star or streak processing for an image, from the median length of its brightest blobs."""
    img = as_float_array(image, "image")
    if img.ndim != 2:
        raise InvalidInputError(f"image must be a 2-D array, got shape {img.shape}")
    checked_number(min_streak_fraction, "min_streak_fraction", low=0.0, above_low=True, high=1.0)
    checked_count(brightest, "brightest", 1)
    length_px = median_length_px(img, brightest)
    if np.isnan(length_px):
        return ModeDecision("point", 0.0, "no stars found")
    fraction = length_px / img.shape[1]
    if fraction >= min_streak_fraction:
        return ModeDecision("streak", fraction, f"median streak {100 * fraction:.1f} % of the width")
    return ModeDecision("point", fraction,
                        f"median streak {100 * fraction:.1f} % of the width, below {100 * min_streak_fraction:.0f} %")
