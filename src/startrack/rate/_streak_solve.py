"""Lost-in-space on a streaked frame, then the attitude at mid-exposure and the rate from the
whole frame (issue 19 items 1-2; Sease 2013 §5 item 9).

1. The streaks are found (:mod:`._streak_find`) and the brightest ``lis_streaks`` fitted
   (:mod:`._streak_fit`).
2. Their light centroids, the stars' mean positions over the exposure (their positions at
   mid-exposure to within the path's curvature), are identified lost-in-space
   (:func:`startrack.solve_stars`) with a position tolerance that grows with the streak length
   (:func:`centroid_sigma_px`).
3. The catalog-free rotation most streaks agree with (:func:`.catalog_free.consensus`) is the
   rate hypothesis; every identified streak must agree with the motion that the identified
   attitude and this rate predict for its catalog star (its length and direction, both ends
   within :func:`agreement_tolerance_px`): a streak that does not is a wrong identification,
   and fewer than three agreeing streaks refuse the identification.
4. The attitude at mid-exposure and the rate (and, with ``fit_alpha``, a constant angular
   acceleration) are fitted jointly to those streaks (:mod:`._streak_model`); then, unless that
   fit already knows the rate to :attr:`StreakOptions.enough_rate_uncertainty`, every other
   catalog star of the field bright enough is predicted, its streak fitted in a window around
   the prediction (:mod:`._streak_predict`) and, where it agrees, added; the joint fit is done
   again on all of them.
5. Trust (as :mod:`._trust` for the catalog-free rate): the rate is reported (status OK) only
   when at least :attr:`StreakOptions.min_streaks` streaks are used, the fit's Birge ratio is
   at most :attr:`StreakOptions.max_birge` and the 3-sigma uncertainty of the rate vector is at
   most :attr:`StreakOptions.max_rate_uncertainty` of the rate; otherwise the attitude stands
   and the rate says why not.

The catalog-free rate of :func:`.streak_rate.streak_rate` (OLAE, Sease 2013 ch. 4) stays the
fallback when identification fails: the solution then carries it with status NO_MATCH for the
attitude. One frame does not tell the time order: give ``prior_omega_rad_s`` (a gyro, the
previous frame) to order it (``time_order_known``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..attitude import roll_cross_boresight
from ..camera import Camera
from ..errors import (
    InvalidInputError,
    check_bool,
    check_finite,
    check_instance,
    check_int,
    check_non_negative,
    check_positive,
    require,
)
from ..frames import radec_roll_from_rotation
from ..identify import MethodName, check_method, field_stars
from ..results import AttitudeSolution, StarMatches, Status
from ..units import DEG
from ._catalog_free import consensus
from ._estimate import RateEstimate, checked_exposure, checked_prior, failed
from ._streak_find import StreakCandidates, find_streak_candidates, finite_frame
from ._streak_fit import StreakFits, first_guesses, fit_pixels, fit_streaks
from ._streak_model import JointFit, Timing, fit_joint, predict
from ._streak_predict import Field, Identified, concatenated, fit_predicted, v_mags, zero_point
from ._streak_screen import typical
from ._trust import consensus_tolerance_px

if TYPE_CHECKING:
    from astropy.time import Time

METHOD = "streak joint fit"


@dataclass(frozen=True)
class StreakOptions:
    """Settings of the streak path.

    Attributes
    ----------
    psf_sigma_px : float
        First guess of the blur (px).
    lis_streaks : int
        Brightest candidate streaks fitted for the identification (twice as many when they do
        not identify: :data:`LIS_ATTEMPTS`).
    max_streaks : int
        Most streaks in the joint fit (identified plus predicted).
    catalog_max_mag : float
        Faintest catalog star whose streak is predicted and fitted (V).
    fit_alpha : bool
        Fit a constant angular acceleration too.
    min_streaks : int
        Fewest streaks for an attitude, and for a rate.
    max_rate_uncertainty : float
        Largest 3-sigma uncertainty of the rate vector, as a fraction of the rate, for a rate
        with status OK.
    enough_rate_uncertainty : float
        The field's other catalog stars are predicted and fitted only when the joint fit of the
        identified streaks leaves a 3-sigma uncertainty of the rate vector (fraction of the rate)
        above this, misfits (Birge ratio over ``max_birge``) or has fewer than
        :data:`ENOUGH_MIN_STREAKS` streaks: at 0.5 % the rate is known to a sixth of the 1 %
        target of issue 19 and more streaks would cost time on the frames whose long streaks
        make them slowest. 0 always fits them.
    max_birge : float
        Largest rms whitened residual of the joint fit for a rate with status OK.
    gain_e_per_adu : float or None
        The camera's gain, for the photon noise in the weights; None estimates it from the fits.
    line_time_s : float
        Rolling shutter: delay between the starts of consecutive rows (s); 0 for a global shutter.
    pixel_aspect : float or None
        As :func:`startrack.solve_stars`' (without a camera): square pixels (1.0) by default, since
        an aspect fitted to the streaks' light centroids trades with the roll (a 0.13 % aspect
        made a 95 arcsec roll error in a 12 deg field); None lets the identification fit it.
    """

    psf_sigma_px: float = 1.0
    lis_streaks: int = 12
    max_streaks: int = 40
    catalog_max_mag: float = 7.5
    fit_alpha: bool = False
    min_streaks: int = 3
    max_rate_uncertainty: float = 0.03
    enough_rate_uncertainty: float = 0.005
    max_birge: float = 3.0
    gain_e_per_adu: float | None = None
    line_time_s: float = 0.0
    pixel_aspect: float | None = 1.0

    def __post_init__(self) -> None:
        """Refuse a setting the streak path cannot use (NaN, infinite, a wrong type), naming it."""
        check_positive(self, ("psf_sigma_px", "max_rate_uncertainty", "max_birge"))
        check_positive(self, ("gain_e_per_adu", "pixel_aspect"), optional=True)
        check_non_negative(self, ("enough_rate_uncertainty", "line_time_s"))
        check_finite(self, ("catalog_max_mag",))
        check_int(self, ("lis_streaks", "max_streaks", "min_streaks"), 3)
        check_bool(self, ("fit_alpha",))

    @property
    def shot(self) -> float | None:
        return None if self.gain_e_per_adu is None else 1.0 / self.gain_e_per_adu


def _nan3() -> NDArray[np.float64]:
    return np.full(3, np.nan)


@dataclass(frozen=True)
class StreakSolution(AttitudeSolution):
    """An :class:`~startrack.results.AttitudeSolution` of a streaked frame (``mode`` "streak").

    Extra attributes
    ----------------
    exposure_s, line_time_s : float
        The exposure (NaN when unknown: the rate is then per exposure only, see ``turn_rad``) and
        the rolling-shutter line time.
    t_mid_s : float
        When the attitude holds: the frame's mid-exposure, seconds after the start of row 0's
        exposure (the middle row's mid-exposure with a rolling shutter).
    time_mid : astropy.time.Time or None
        The same as an absolute time, when the image header gives the start of the exposure.
    rate : RateEstimate
        The rate (camera frame, rad/s) with its covariance, or why it is not trusted.
    alpha_rad_s2 : ndarray, shape (3,)
        Fitted angular acceleration (zero when not fitted).
    turn_rad : ndarray, shape (3,)
        The rotation vector turned during the exposure, ``omega T`` (known without ``exposure_s``).
    time_order_known : bool
        The rate's sign was chosen by a prior rate; else one frame cannot tell it.
    streaks : StreakFits or None
        Every streak fitted (identification candidates, then predicted ones).
    streak_index : ndarray of int, shape (K,)
        Rows of ``streaks`` in the joint fit (``matches`` lists their stars, in the same order).
    birge : float
        Rms whitened residual of the joint fit per degree of freedom.
    stage_s, stage_cpu_s : dict
        Wall and process time (s) of each stage: "find", "fit", "identify", "joint", "predicted".
    """

    mode: str = "streak"
    exposure_s: float = float("nan")
    line_time_s: float = 0.0
    t_mid_s: float = float("nan")
    time_mid: object | None = None
    rate: RateEstimate = field(default_factory=lambda: failed(Status.NO_MATCH, "no rate", METHOD))
    alpha_rad_s2: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    turn_rad: NDArray[np.float64] = field(default_factory=_nan3)
    time_order_known: bool = False
    streaks: StreakFits | None = None
    streak_index: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    birge: float = float("nan")
    stage_s: dict = field(default_factory=dict)
    stage_cpu_s: dict = field(default_factory=dict)

    @property
    def n_streaks(self) -> int:
        return int(self.streak_index.size)

    @property
    def rate_sigma_roll_cross_deg_s(self) -> tuple[float, float]:
        """1-sigma of the rate about the boresight (roll) and across it (rms of x, y), deg/s."""
        cov = self.rate.covariance_rad2_s2
        if cov is None:
            return (math.nan, math.nan)
        roll, cross = roll_cross_boresight(cov)
        return float(roll / DEG), float(cross / DEG)


def header_exposure_s(header) -> float | None:
    """The exposure time an image header states (FITS ``EXPTIME`` or ``EXPOSURE``, EXIF
    ``ExposureTime``; seconds), or None."""
    for key in ("EXPTIME", "EXPOSURE", "ExposureTime"):
        value = header.get(key) if header else None
        if value is None:
            continue
        try:
            seconds = float(value)
        except (TypeError, ValueError):
            continue
        if math.isfinite(seconds) and seconds > 0:
            return seconds
    return None


def centroid_sigma_px(length_px: ArrayLike) -> float:
    """The identification's position tolerance (1 sigma, px) for streaks of these lengths:
    0.5 px plus 0.4 % of the median length (the light centroid departs from the mid-exposure
    position with the path's curvature and speed changes, which grow with the length)."""
    return 0.5 + 0.004 * float(np.median(np.asarray(length_px, dtype=float)))


def agreement_tolerance_px(length_px: ArrayLike) -> NDArray[np.float64]:
    """How far (px) an identified streak's ends and centroid may lie from those the identified
    attitude and the consensus rate predict: 2 px + 3 % of its length."""
    return 2.0 + 0.03 * np.asarray(length_px, dtype=float)


def checked_options(options: object) -> StreakOptions:
    """``options`` (None: the defaults) as :class:`StreakOptions`; another class is refused."""
    return StreakOptions() if options is None else check_instance(options, StreakOptions, "options of the streak path")


def solve_streaked(
    image: ArrayLike,
    *,
    camera: Camera | None = None,
    fov_deg: float | None = None,
    fov_range_deg: tuple[float, float] | None = None,
    exposure_s: float | None = None,
    epoch: Time | float | None = None,
    prior_omega_rad_s: ArrayLike | None = None,
    options: StreakOptions | None = None,
    method: MethodName = "quads",
) -> StreakSolution:
    """Lost-in-space attitude at mid-exposure and the rate of a streaked frame (module docstring).

    Parameters
    ----------
    image : array_like, shape (H, W)
        The frame (counts).
    camera, fov_deg, fov_range_deg, epoch, method
        As in :func:`startrack.solve_stars` (a camera fixes the focal length; otherwise it is
        fitted by the identification).
    exposure_s : float, optional
        Exposure time (s); None gives the turn per exposure only (``turn_rad``).
    prior_omega_rad_s : array_like, shape (3,), optional
        A rough rate of the right sign (camera frame) that orders the exposure in time.
    options : StreakOptions, optional
        Settings of the streak path (another class is refused, naming the class given).

    Returns
    -------
    StreakSolution
        Status TOO_FEW_STARS (fewer than three clean streaks), NO_MATCH (not identified, or the
        identification disagrees with the streaks' motion; ``rate`` then holds the catalog-free
        rate) or OK, with ``rate`` OK or saying why the rate is not trusted.
    """
    method = check_method(method)
    opts = checked_options(options)
    img = np.asarray(image)
    if img.ndim != 2:
        raise InvalidInputError(f"image must be a 2-D array (H, W), got shape {img.shape}")
    img = finite_frame(img)  # NaN and infinite pixels filled: the fits have no mask
    prior_omega_rad_s = checked_prior(prior_omega_rad_s)
    clock = Stages()
    timing = _timing(exposure_s, opts.line_time_s, img.shape[0])
    cand = find_streak_candidates(img)
    clock.mark("find")
    pixels, saturation = fit_pixels(img)
    guesses = _ordered_guesses(pixels, cand, opts)
    fits, lis, good = None, None, np.zeros(0, dtype=np.int64)
    for attempt in range(LIS_ATTEMPTS):  # more of the fainter candidates when the brightest do not identify
        fits = _lis_fits(pixels, saturation, cand, guesses, opts.lis_streaks * (attempt + 1), fits, opts)
        clock.mark("fit")
        good = np.flatnonzero(fits.ok & typical(fits))
        if good.size < opts.min_streaks:
            continue
        lis = _identify(fits, good, fits.measurements()[0], img.shape, camera, fov_deg, fov_range_deg, epoch, method,
                        opts.pixel_aspect)
        clock.mark("identify")
        if lis.solved or len(fits) >= len(guesses[0]):
            break
    fits = require(fits, "the streak fits")  # (the loop runs at least once)
    if lis is None:
        return failed_solution(Status.TOO_FEW_STARS, f"{good.size} clean streaks ({opts.min_streaks} needed)", fits,
                               timing, clock)
    measured, cov = fits.measurements()
    omega0, agree0 = _consensus_rate(lis.camera or camera, fits, good, timing)
    if not lis.solved:
        return failed_solution(lis.status, lis.reason, fits, timing, clock, omega0 if agree0 >= 3 else None)
    rows = good[lis.matches.det_index]
    keep = _agreeing(lis, fits, rows, measured, omega0, timing)
    if keep.sum() < opts.min_streaks:
        return failed_solution(Status.NO_MATCH, f"only {keep.sum()} of {rows.size} identified streaks move as the "
                               "frame's streaks do: the identification is not confirmed", fits, timing, clock, omega0)
    fit_focal = camera is None
    lis_camera = require(lis.camera, "the identification's camera")
    joint = fit_joint(lis_camera, lis.matches.cat_vectors[keep], measured[rows[keep]], cov[rows[keep]],
                      lis.rot_cam_from_icrs, omega0, timing, fit_alpha=opts.fit_alpha, fit_focal=fit_focal)
    clock.mark("joint")
    found = Identified(fits, rows[keep], lis.matches.cat_vectors[keep], lis.matches.hip[keep])
    found, joint = _extended(pixels, saturation, found, cand, joint, timing, opts, lis.epoch_jyear, fit_focal, clock)
    return streak_solution(found, joint, timing, opts, prior_omega_rad_s, exposure_s, clock,
                           false_match_prob=lis.false_match_prob, epoch_jyear=lis.epoch_jyear,
                           epoch_source=lis.epoch_source)


class Stages:
    """Wall and process (CPU) time of each stage of a solve (s): :meth:`mark` ends the current one."""

    def __init__(self) -> None:
        self.start = self._last = time.perf_counter()
        self._last_cpu = time.process_time()
        self.times: dict[str, float] = {}
        self.cpu: dict[str, float] = {}

    def mark(self, name: str) -> None:
        now, cpu = time.perf_counter(), time.process_time()
        self.times[name] = self.times.get(name, 0.0) + now - self._last
        self.cpu[name] = self.cpu.get(name, 0.0) + cpu - self._last_cpu
        self._last, self._last_cpu = now, cpu

    @property
    def total_s(self) -> float:
        return time.perf_counter() - self.start


def _timing(exposure_s: float | None, line_time_s: float, height: int) -> Timing:
    if exposure_s is None:
        return Timing(1.0, 0.0, height)
    exposure_s = checked_exposure(exposure_s)
    if not (math.isfinite(line_time_s) and line_time_s >= 0):
        raise InvalidInputError(f"line_time_s must be zero or positive seconds, got {line_time_s!r}")
    return Timing(float(exposure_s), float(line_time_s), int(height))


LIS_ATTEMPTS = 2
"""Identification attempts: the brightest ``lis_streaks`` candidates, then twice as many."""


def _ordered_guesses(img: NDArray, cand: StreakCandidates, opts: StreakOptions):
    """The candidates' first guesses, brightest first (light per guess: amplitude x length)."""
    start, own, reach, band = first_guesses(img, cand, opts.psf_sigma_px)
    order = np.argsort(-start[:, 5] * np.hypot(start[:, 2], start[:, 3]), kind="stable")
    return start[order], own[order], reach[order], band[order]


def _lis_fits(img: NDArray, saturation: float, cand: StreakCandidates, guesses, count: int, done: StreakFits | None,
              opts: StreakOptions) -> StreakFits:
    """Fits of the first ``count`` guesses (those of ``done`` kept, the others fitted now) to
    the pixels of :func:`.streak_fit.fit_pixels`."""
    start, own, reach, band = guesses
    first = 0 if done is None else len(done)
    new = slice(first, min(count, len(start)))
    fits = fit_streaks(img, start[new], reach[new], band[new], noise=cand.noise, labels=cand.labels,
                       bin_px=cand.bin_px, own=own[new], shot=opts.shot if done is None else done.shot,
                       saturation=saturation)
    return fits if done is None else concatenated(done, fits)


def _identify(fits, good, measured, shape, camera, fov_deg, fov_range_deg, epoch, method,
              pixel_aspect) -> AttitudeSolution:
    """solve_stars on the light centroids of the clean streaks, brightest first."""
    from ..identify import MatcherOptions
    from ..solve import solve_stars

    sigma = centroid_sigma_px(fits.length_px[good])
    options = MatcherOptions(centroid_sigma_px=sigma, match_radius_px=max(2.0, 4.0 * sigma)) \
        if method == "quads" else None
    size = {} if camera is not None else {"width": int(shape[1]), "height": int(shape[0]),
                                          "pixel_aspect": pixel_aspect}
    xy = measured[good, 4:6]
    return solve_stars(xy[:, 0], xy[:, 1], camera=camera, fov_deg=fov_deg, fov_range_deg=fov_range_deg,
                       flux=fits.flux[good], epoch=epoch, method=method, options=options, **size)


def _consensus_rate(camera: Camera | None, fits: StreakFits, good: NDArray, timing: Timing
                    ) -> tuple[NDArray[np.float64], int]:
    """The catalog-free rate most clean streaks agree with (sign arbitrary) and how many agree."""
    if camera is None or good.size < 2:
        return np.full(3, np.nan), 0
    ends = fits.ends_xy[good]
    va = camera.pixel_to_vector(ends[:, 0, 0], ends[:, 0, 1])
    vb = camera.pixel_to_vector(ends[:, 1, 0], ends[:, 1, 1])
    sigma = np.max(fits.end_sigma_px()[good], axis=1)
    found = consensus(va, vb, consensus_tolerance_px(sigma) / camera.fx)
    norm = np.linalg.norm(found.gibbs)
    rotvec = found.gibbs * (2.0 * np.arctan(norm) / norm) if norm > 0 else np.zeros(3)
    return -rotvec / timing.exposure_s, int(found.used.sum())


def _agreeing(lis: AttitudeSolution, fits: StreakFits, rows: NDArray, measured: NDArray, omega0: NDArray,
              timing: Timing) -> NDArray[np.bool_]:
    """Identified streaks whose ends and centroid agree with the motion of their catalog star
    under the identified attitude and the consensus rate (either time order)."""
    if not np.all(np.isfinite(omega0)):
        return np.zeros(rows.size, dtype=bool)
    lis_camera = require(lis.camera, "the identification's camera")
    predicted = predict(lis_camera, lis.rot_cam_from_icrs, omega0, np.zeros(3), lis.matches.cat_vectors, timing)
    m = measured[rows]
    swapped = m[:, [2, 3, 0, 1, 4, 5]]

    def worst(a):
        return np.max(np.linalg.norm((a - predicted).reshape(-1, 3, 2), axis=2), axis=1)

    return np.minimum(worst(m), worst(swapped)) <= agreement_tolerance_px(fits.length_px[rows])


def extend(img: NDArray, found: Identified, joint: JointFit, timing: Timing, field: Field, *, noise: float,
           background: float, opts: StreakOptions, fit_focal: bool, saturation: float) -> tuple[Identified, JointFit]:
    """Add the predicted streaks of the field's other catalog stars that agree with the joint
    fit (one tight pass each, :func:`.streak_predict.fit_predicted`), and fit again; unless the
    joint fit already knows the rate well enough (:attr:`StreakOptions.enough_rate_uncertainty`)
    or has no room (``max_streaks``). ``img`` and ``saturation`` are :func:`.streak_fit.fit_pixels`'
    pair: the float pixels no longer show the ADC's ceiling, so it is given."""
    room = opts.max_streaks - found.rows.size
    if room <= 0 or _known_enough(joint, opts):
        return found, joint
    blur = float(np.median(found.fits.blur_px[found.rows]))
    zero = zero_point(found.fits.flux[found.rows], v_mags(found.hips))
    index, more = fit_predicted(img, joint.camera, field.vectors, joint.rot_mid, joint.omega_rad_s, joint.alpha_rad_s2,
                                timing, noise=noise, background=background, blur_px=blur, shot=found.fits.shot,
                                slack_px=1.0, tolerance_px=3.0, limit=room, flux=field.flux(zero),
                                wanted=~np.isin(field.hips, found.hips), saturation=saturation)
    if more is None or not np.any(more.ok):
        return found, joint
    found = found.joined(more, field.vectors[index], field.hips[index])
    measured, cov = found.measurements()
    joint = fit_joint(joint.camera, found.stars, measured, cov, joint.rot_mid, joint.omega_rad_s, timing,
                      fit_alpha=opts.fit_alpha, fit_focal=fit_focal)
    return found, joint


ENOUGH_MIN_STREAKS = 5
"""Fewest streaks in a joint fit whose uncertainty may stop the fitting of predicted streaks
(:attr:`StreakOptions.enough_rate_uncertainty`): with 3 or 4 the fit's own covariance is not to be
trusted that far (in the streak-mode campaign a 3-streak fit claimed a 0.5 % rate and missed the
roll by 140 arcsec, ten times its sigma)."""


def _known_enough(joint: JointFit, opts: StreakOptions) -> bool:
    """Whether the joint fit already knows the rate to ``opts.enough_rate_uncertainty`` from at
    least :data:`ENOUGH_MIN_STREAKS` streaks that fit one rotation (Birge ratio at most ``max_birge``)."""
    return bool(joint.used.sum() >= ENOUGH_MIN_STREAKS and joint.birge <= opts.max_birge
                and relative_rate_sigma3(joint) <= opts.enough_rate_uncertainty)


def _extended(img, saturation, found, cand, joint, timing, opts, epoch_jyear, fit_focal, clock):
    """:func:`extend` with the catalog stars of the field around the joint fit's attitude."""
    stars = field_stars(opts.catalog_max_mag, epoch_jyear)
    turn = float(np.linalg.norm(joint.omega_rad_s)) * timing.exposure_s
    field = Field.around(stars, joint.camera, joint.rot_mid, turn)
    found, joint = extend(img, found, joint, timing, field, noise=cand.noise, background=cand.background, opts=opts,
                          fit_focal=fit_focal, saturation=saturation)
    clock.mark("predicted")
    return found, joint


def _ordered_by(joint: JointFit, prior: ArrayLike | None) -> tuple[NDArray, bool]:
    """(sign, known): the rate's sign that agrees with a prior rate."""
    w = checked_prior(prior)
    if w is None:
        return np.ones(1), False
    return np.array([1.0 if np.dot(joint.omega_rad_s, w) >= 0 else -1.0]), True


def relative_rate_sigma3(joint: JointFit) -> float:
    """The 3-sigma uncertainty of the joint fit's rate vector over the rate's size (large near rest)."""
    return 3.0 * math.sqrt(float(np.trace(joint.rate_covariance))) / max(float(np.linalg.norm(joint.omega_rad_s)),
                                                                         1e-300)


def rate_verdict(joint: JointFit, opts: StreakOptions, known_exposure: bool) -> tuple[Status, str]:
    """Whether the joint fit's rate is trusted (module docstring, item 5)."""
    used = int(joint.used.sum())
    if used < opts.min_streaks:
        return Status.TOO_FEW_STARS, f"{used} streaks in the fit ({opts.min_streaks} needed)"
    if not known_exposure:
        return Status.DEGENERATE, "the exposure time is unknown: the turn per exposure is in turn_rad"
    if joint.birge > opts.max_birge:
        return Status.DEGENERATE, f"the streaks misfit one rotation (rms {joint.birge:.1f} sigma > {opts.max_birge:g})"
    relative = relative_rate_sigma3(joint)
    if relative > opts.max_rate_uncertainty:
        return Status.DEGENERATE, (f"rate uncertain by {100 * relative:.1f} % (3 sigma, > "
                                   f"{100 * opts.max_rate_uncertainty:g} %): too few or too imprecise streaks")
    return Status.OK, ""


def streak_solution(found: Identified, joint: JointFit, timing: Timing, opts: StreakOptions, prior: ArrayLike | None,
                    exposure_s: float | None, clock: Stages, **extra) -> StreakSolution:
    """The StreakSolution of a joint fit to identified streaks (``extra``: more solution fields)."""
    sign, known = _ordered_by(joint, prior)
    omega = sign[0] * joint.omega_rad_s
    used = joint.used
    status, reason = rate_verdict(joint, opts, exposure_s is not None)
    rate = RateEstimate(status, reason, omega if status is Status.OK else np.full(3, np.nan),
                        joint.rate_covariance, METHOD, used)
    ra, dec, roll = radec_roll_from_rotation(joint.rot_mid)
    rows = found.rows[used].astype(np.int64)
    matches = StarMatches(Status.OK, det_index=rows, hip=found.hips[used].astype(np.int64),
                          cat_vectors=found.stars[used], false_match_prob=extra.get("false_match_prob", 1.0))
    return StreakSolution(
        status=Status.OK, rot_cam_from_icrs=joint.rot_mid, covariance_rad2=joint.attitude_covariance,
        ra_deg=math.degrees(ra), dec_deg=math.degrees(dec), roll_deg=math.degrees(roll), fov_deg=joint.camera.fov_deg,
        camera=joint.camera, matches=matches, residuals_arcsec=_residuals_arcsec(joint, joint.camera),
        solve_time_s=clock.total_s, exposure_s=math.nan if exposure_s is None else float(exposure_s),
        line_time_s=timing.line_time_s, t_mid_s=timing.mid_after_start_s if exposure_s is not None else math.nan,
        rate=rate, alpha_rad_s2=joint.alpha_rad_s2, turn_rad=omega * timing.exposure_s, time_order_known=known,
        streaks=found.fits, streak_index=rows, birge=joint.birge, stage_s=dict(clock.times),
        stage_cpu_s=dict(clock.cpu), **extra)


def _residuals_arcsec(joint: JointFit, camera: Camera) -> NDArray[np.float64]:
    """Each used streak's rms distance of its measured ends and centroid from the model (arcsec)."""
    diff = (joint.measured - joint.predicted)[joint.used].reshape(-1, 3, 2)
    return np.sqrt(np.mean(np.sum(diff**2, axis=2), axis=1)) * camera.pixel_scale_arcsec


def failed_solution(status: Status, reason: str, fits: StreakFits, timing: Timing, clock: Stages,
            omega: NDArray | None = None) -> StreakSolution:
    """No attitude; the catalog-free consensus rate when there is one (status DEGENERATE: not
    checked by the trust rules of :mod:`._trust`)."""
    if omega is not None and np.all(np.isfinite(omega)):
        rate = RateEstimate(Status.DEGENERATE, "catalog-free consensus rate, not identified: time order and "
                            "uncertainty unknown", omega, None, "catalog-free consensus")
    else:
        rate = failed(status, reason, METHOD)
    return StreakSolution(status=status, reason=reason, solve_time_s=clock.total_s, rate=rate,
                          streaks=fits, line_time_s=timing.line_time_s, stage_s=dict(clock.times),
                          stage_cpu_s=dict(clock.cpu))


def replace_rate(solution: StreakSolution, rate: RateEstimate) -> StreakSolution:
    """The solution with another rate estimate (e.g. the catalog-free OLAE rate)."""
    return replace(solution, rate=rate)
