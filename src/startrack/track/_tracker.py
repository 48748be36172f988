"""The Tracker: a state machine over a sequence of frames (DESIGN.md §1; Huffman 2006 §1.3 mode
logic, Samaan 2002 Eq. 1–3 predictive loop, Jacobs 1995 §4 tracking).

* No attitude yet (or tracking just failed): lost-in-space (:func:`startrack.solve_stars`).
* An attitude from the previous frame: predict this frame's attitude with the rate (from a gyro
  when given, otherwise from the last two attitudes, smoothed), identify stars in windows around
  their predicted positions (:func:`.windows.match_in_windows`), confirm with the geometry of the
  matched stars (enough stars, residuals at the noise level). If that fails, fall back to
  lost-in-space in the same frame.

A lost-in-space solve with an unknown FOV fixes the camera (its fitted focal length) for the
frames after it.

Given a :class:`startrack.CameraRig` (``Tracker(rig=...)``), the tracker follows the rig's body
attitude with :meth:`Tracker.update_rig` (:class:`startrack.multihead._tracking.RigTracker`): every
head's windows predicted from the joint attitude and rate, tracking while at least one head sees
``min_stars`` stars, and each step says which heads contributed.

Streaked frames (:meth:`Tracker.update_image` with an exposure time, given or read from the image
header): the mode switches automatically between point stars and streaks (Sease 2013  item
9) by the length a star smears during the exposure, from the rate (the gyro's or the tracker's,
``T (f |omega_xy| + r |omega_z|)`` with r the half-diagonal) or, before there is one, measured in
the image; with hysteresis, streak mode from :attr:`TrackerOptions.streak_on_px` and point mode
again below :attr:`TrackerOptions.streak_off_px`. In streak mode a frame is solved from its streaks
(:mod:`startrack.rate._streak_track`: every streak predicted from the previous attitude and rate
and fitted in a window; lost-in-space on the streaks, :func:`startrack.rate._streak_solve.
solve_streaked`, when that fails), which gives the attitude at mid-exposure and the rate; a frame
streak mode cannot solve is tried in point mode, and the other way round.

A tracking step keeps its attitude as a quaternion and predicts, fits and differences attitudes
with :mod:`._quaternions` (the same kinematics as :func:`startrack.attitude._propagation.propagate`
and :func:`startrack.rate._from_attitudes.rate_between`, without scipy's per-call overhead); the
catalog stars around the boresight are kept from frame to frame (:class:`.windows.WindowMatcher`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Final, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import (
    InvalidInputError,
    check_finite,
    check_instance,
    check_int,
    check_non_negative,
    check_positive,
    is_real_number,
    require,
)
from ..frames import radec_roll_from_rotation
from ..identify import field_stars
from ..rate import SmearLimits, image_smear_px, usable_for_prediction
from ..results import Status
from ..solve import epoch_jyear, solve_stars
from ._inputs import checked_exposure, checked_flux, checked_rate, checked_stars, checked_time
from ._quaternions import Quat, quat_conjugate, quat_matrix, quat_product, quat_rotvec, rotvec_quat
from ._windows import WindowMatcher

if TYPE_CHECKING:
    from astropy.time import Time

    from ..io import Image
    from ..rate import StreakOptions

StepMode = Literal["lost-in-space", "tracking", "streak lost-in-space", "streak tracking"]
"""How the Tracker solved a frame (:attr:`TrackStep.mode`)."""
STEP_MODES: tuple[StepMode, ...] = get_args(StepMode)
"""The names of :data:`StepMode`, in its order."""
LOST_IN_SPACE: Final = "lost-in-space"
"""A step solved lost-in-space (no usable prediction: the first frame, or tracking failed)."""
TRACKING: Final = "tracking"
"""A step solved from the prediction of the last attitude and rate (the window matcher)."""
STREAK_LOST_IN_SPACE: Final = "streak lost-in-space"
"""A streaked frame solved lost-in-space from its streaks (:mod:`startrack.rate._streak_solve`)."""
STREAK_TRACKING: Final = "streak tracking"
"""A streaked frame solved from the predicted streaks of the last attitude and rate."""
FrameMode = Literal["point", "streak"]
"""The kind of image :meth:`Tracker.update_image` is in (:attr:`Tracker.mode`; module docstring)."""
POINT_MODE: Final = "point"
STREAK_MODE: Final = "streak"
MIN_TRACKED_STARS: Final = 2
"""Smallest :attr:`TrackerOptions.min_stars`: two stars (in different directions) are the fewest
that fix an attitude (the window fit's q-method, the rig's joint fit); with fewer the fit has no
unique answer (an empty frame has none at all, one star leaves the roll about it free)."""


@dataclass(frozen=True)
class TrackerOptions:
    """Settings of the Tracker.

    Attributes
    ----------
    min_stars : int
        Fewest matched stars for a tracked attitude (an integer >= :data:`MIN_TRACKED_STARS`, 2).
    window_px : float
        Search half-window around each predicted star when the rate is known (px, > 0).
    max_rate_deg_s : float
        Largest rate expected; sets the window when the rate is not known yet (deg/s, >= 0).
    rate_error_fraction : float
        Assumed relative error of the rate estimate; widens the window with the motion (>= 0).
    match_px : float
        Match radius once the attitude is refitted to the window matches (px, > 0).
    max_residual_px : float
        A tracked attitude whose matched stars leave a larger rms residual is rejected (px, > 0).
    rate_gain : float
        Weight of the newest frame-to-frame rate in the smoothed rate (0 < gain <= 1).
    catalog_max_mag : float
        Faintest catalog star predicted (V, finite).
    target_stars : int or None
        For :meth:`Tracker.update_image`: detect with the dynamic threshold aiming at this many
        stars (an integer >= 1; None: the detector's default k-sigma threshold).
    streak_on_px, streak_off_px : float
        Mode switching of :meth:`Tracker.update_image` (module docstring): streak mode from a
        smear of ``streak_on_px`` (px), point mode again below ``streak_off_px``.
    streak : StreakOptions or None
        Settings of the streak path (None: the defaults of
        :class:`startrack.rate._streak_solve.StreakOptions`).

    Raises
    ------
    InvalidInputError
        A setting of the wrong type, NaN, infinite or out of the range above, naming it.
    """

    min_stars: int = 5
    window_px: float = 8.0
    max_rate_deg_s: float = 6.0
    rate_error_fraction: float = 0.2
    match_px: float = 2.0
    max_residual_px: float = 1.0
    rate_gain: float = 0.5
    catalog_max_mag: float = 9.5
    target_stars: int | None = None
    streak_on_px: float = 12.0
    streak_off_px: float = 8.0
    streak: StreakOptions | None = None

    def __post_init__(self) -> None:
        """Refuse a setting the tracker cannot use (a wrong type, NaN, infinite or out of its range),
        naming it and its valid range."""
        check_int(self, ("min_stars",), MIN_TRACKED_STARS)
        check_int(self, ("target_stars",), 1, optional=True)
        check_positive(self, ("window_px", "match_px", "max_residual_px"))
        check_non_negative(self, ("max_rate_deg_s", "rate_error_fraction"))
        check_finite(self, ("catalog_max_mag",))
        if not (is_real_number(self.rate_gain) and 0 < self.rate_gain <= 1):
            raise InvalidInputError(f"rate_gain must be a number with 0 < rate_gain <= 1 (the newest rate's weight), "
                                    f"got {self.rate_gain!r}")
        if self.streak is not None:
            from ..rate import StreakOptions

            check_instance(self.streak, StreakOptions, "TrackerOptions.streak")
        if not (is_real_number(self.streak_on_px) and is_real_number(self.streak_off_px)
                and 0 < self.streak_off_px <= self.streak_on_px):
            raise InvalidInputError(f"streak_off_px must be positive and at most streak_on_px (hysteresis), got "
                                    f"{self.streak_off_px!r} and {self.streak_on_px!r}")


@dataclass(frozen=True)
class TrackStep:
    """What the Tracker made of one frame."""

    t_s: float
    mode: StepMode
    status: Status
    reason: str = ""
    rot_cam_from_icrs: Rotation | None = None
    rate_rad_s: NDArray[np.float64] | None = None
    n_matched: int = 0
    residual_rms_px: float = float("nan")
    time_s: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def radec_roll_deg(self) -> tuple[float, float, float]:
        """Boresight RA, Dec and roll in degrees (NaN when there is no attitude)."""
        if self.rot_cam_from_icrs is None:
            return (math.nan, math.nan, math.nan)
        ra, dec, roll = (float(np.degrees(a)) for a in radec_roll_from_rotation(self.rot_cam_from_icrs))
        return ra, dec, roll


def _checked_options(options: object) -> TrackerOptions:
    """``options`` (None: the defaults) as :class:`TrackerOptions`; another class is refused."""
    return TrackerOptions() if options is None else check_instance(options, TrackerOptions, "options of the Tracker")


class Tracker:
    """Follows the attitude over a sequence of star lists (or images, see :meth:`update_image`).

    Parameters
    ----------
    camera : Camera, optional
        A calibrated camera. Otherwise give ``width``, ``height`` and ``fov_deg`` or
        ``fov_range_deg`` (the first lost-in-space solve then fixes the focal length).
    epoch : float or astropy Time, optional
        Catalog epoch (Julian year); default J2000.0.
    options : TrackerOptions, optional
    rig : CameraRig, optional
        Follow a rig of camera heads instead of one camera (give no camera, size or FOV); frames go
        to :meth:`update_rig`.
    """

    def __init__(self, *, camera: Camera | None = None, width: int | None = None, height: int | None = None,
                 fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None,
                 epoch: Time | float | None = None, options: TrackerOptions | None = None, rig=None):
        self._rig = None
        self.options = _checked_options(options)
        if rig is not None:
            if any(v is not None for v in (camera, width, height, fov_deg, fov_range_deg)):
                raise InvalidInputError("a rig has its cameras: give rig, or a camera (or size and FOV), not both")
            from ..multihead import RigTracker  # the rig mode builds on this module

            self._rig = RigTracker(rig, epoch=epoch, options=options)
        elif camera is None and (width is None or height is None):
            raise InvalidInputError("give a camera, or the image width and height (and a FOV or FOV range)")
        self._lis_kwargs: dict[str, Any] = {"width": width, "height": height, "fov_deg": fov_deg,
                                            "fov_range_deg": fov_range_deg, "epoch": epoch}
        self._camera = camera
        self._rot: Rotation | None = None
        self._quat: Quat | None = None
        self._t: float | None = None
        self._rate: NDArray | None = None
        self._epoch = epoch
        self._matcher: WindowMatcher | None = None
        self._mode: FrameMode = POINT_MODE
        self._streak_memory: dict = {}
        self._last_measured: NDArray | None = None

    # --- public ---------------------------------------------------------------------------------
    def update(self, x: ArrayLike, y: ArrayLike, t_s: float, *, flux: ArrayLike | None = None,
               gyro_rate_rad_s: ArrayLike | None = None) -> TrackStep:
        """Process one frame's star list (our pixel convention) taken at time ``t_s`` (seconds)."""
        if self._rig is not None:
            raise InvalidInputError("this Tracker follows a rig: give each head's stars to update_rig")
        t0 = time.perf_counter()
        t_s = checked_time(t_s)
        x, y = checked_stars(x, y)
        if flux is not None:
            order = np.argsort(-checked_flux(flux, x.shape), kind="stable")
            x, y = x[order], y[order]
        if gyro_rate_rad_s is not None:
            self._rate = checked_rate(gyro_rate_rad_s)
        step = self._track(x, y, t_s) if self._rot is not None and self._camera is not None else None
        if step is None:
            step = self._lost_in_space(x, y, t_s)
        return _with_time(step, time.perf_counter() - t0)

    def update_image(self, image, t_s: float, *, detector=None, gyro_rate_rad_s=None,
                     streak_exposure_s: float | None = None, streak_bias_px: float | None = None) -> TrackStep:
        """Detect the stars of an image (array or path) and :meth:`update` with them, or, when
        the stars smear, solve it from its streaks (module docstring).

        ``t_s`` is the frame's time tag: its mid-exposure (Samaan 2002 eq. 6), which the attitude
        of a streaked frame refers to. The exposure ``streak_exposure_s`` (s; default: the image
        header's ``EXPTIME``, ``EXPOSURE`` or EXIF ``ExposureTime``) enables the mode switching;
        without one every frame is processed as point stars. The step's ``extra`` holds
        ``streak_px`` (the smear that chose the mode), ``switched`` (the mode changed at this
        frame) and, in streak mode, ``rate_status``, ``n_streaks`` and ``t_mid_s``.

        With ``streak_bias_px`` (the seed's corner-detector path, kept as it was): a streaked
        image (``choose_mode``) with a known camera gives its own rate
        (:func:`startrack.rate._streak_rate.streak_rate` with Harris ends corrected by
        ``streak_bias_px``; a rate its consistency checks refuse is not used), ordered in time by
        ``gyro_rate_rad_s`` or the tracker's rate; it replaces the gyro rate for this frame and
        the stars are tracked as points.

        Without a ``detector``, stars are detected with :attr:`TrackerOptions.target_stars`:
        None uses the default k-sigma threshold, a number the dynamic threshold that adapts to
        reach that many stars (Huffman 2006 §8.2.3).
        """
        from ..detect import StarDetector
        from ..io import read_image
        from ..rate import header_exposure_s

        t_s, streak_exposure_s = checked_time(t_s), checked_exposure(streak_exposure_s)
        if detector is not None:
            check_instance(detector, StarDetector, "detector")
        if gyro_rate_rad_s is not None:
            gyro_rate_rad_s = checked_rate(gyro_rate_rad_s)
        img = read_image(image)
        data = img.data
        if streak_exposure_s is not None and streak_bias_px is not None:
            gyro_rate_rad_s = self._streak_rate(data, streak_exposure_s, streak_bias_px, gyro_rate_rad_s)
            return self._point_image(img, t_s, detector, gyro_rate_rad_s)
        exposure = streak_exposure_s if streak_exposure_s is not None else header_exposure_s(img.header)
        if exposure is None or not exposure > 0:
            return self._point_image(img, t_s, detector, gyro_rate_rad_s)
        return self._switching(data, t_s, float(exposure), detector, gyro_rate_rad_s)

    def _point_image(self, data: NDArray | Image, t_s: float, detector, gyro_rate_rad_s) -> TrackStep:
        """Point-star processing: detect (a JPEG with its noise floor, :meth:`.StarDetector.for_image`),
        then :meth:`update`."""
        from ..detect import StarDetector

        if detector is None:
            target = self.options.target_stars
            detector = StarDetector() if target is None else StarDetector(threshold="dynamic", target_stars=target)
        found = detector.detect(data)
        return self.update(found.x, found.y, t_s, gyro_rate_rad_s=gyro_rate_rad_s)

    def _streak_rate(self, data: NDArray, exposure_s: float, bias_px: float, gyro_rate_rad_s) -> NDArray | None:
        """The rate of a streaked frame (time-ordered by the gyro or tracker rate), else the gyro's."""
        from ..rate import choose_mode, streak_rate

        prior = gyro_rate_rad_s if gyro_rate_rad_s is not None else self._rate
        if self._camera is None or prior is None or choose_mode(data).mode != "streak":
            return gyro_rate_rad_s
        found = streak_rate(data, self._camera, exposure_s, detector="harris", bias_px=bias_px,
                            prior_omega_rad_s=prior)
        return found.rate.omega_rad_s if found.rate.ok and found.time_order_known else gyro_rate_rad_s

    def _switching(self, data: NDArray, t_s: float, exposure_s: float, detector, gyro_rate_rad_s) -> TrackStep:
        """One frame with automatic mode switching (module docstring)."""
        t0 = time.perf_counter()
        if gyro_rate_rad_s is not None:
            self._rate = checked_rate(gyro_rate_rad_s)
        smear = self._smear_px(data, exposure_s)
        previous = self._mode
        if smear >= self.options.streak_on_px or (previous == STREAK_MODE and smear > self.options.streak_off_px):
            self._mode = STREAK_MODE
        else:
            self._mode = POINT_MODE
        streak = self._mode == STREAK_MODE
        step = self._streak_image(data, t_s, exposure_s) if streak else self._point_image(data, t_s, detector, None)
        if not step.status and smear > self.options.streak_off_px:  # the other mode may still solve it
            step = self._point_image(data, t_s, detector, None) if streak else self._streak_image(data, t_s, exposure_s)
        extra = {**step.extra, "streak_px": smear, "switched": self._mode != previous}
        return replace(step, extra=extra, time_s=time.perf_counter() - t0)

    def _smear_px(self, data: NDArray, exposure_s: float) -> float:
        """How far (px) a star smears in the exposure: from the rate when there is one (the
        smoothed rate or the last frame-to-frame one, whichever is faster: the smoothed rate lags
        when the rate changes), else measured in the image (:func:`image_smear_px`)."""
        if self._rate is None:
            return image_smear_px(data)
        camera = self._camera or self._nominal_camera(data)
        half_diagonal = 0.5 * math.hypot(camera.width, camera.height)
        rates = [self._rate] + ([self._last_measured] if self._last_measured is not None else [])
        return max(exposure_s * (camera.fx * math.hypot(w[0], w[1]) + abs(w[2]) * half_diagonal) for w in rates)

    def _nominal_camera(self, data: NDArray) -> Camera:
        """A pinhole camera of the tracker's FOV (or the middle of its FOV range) for the image size."""
        kw = self._lis_kwargs
        fov = kw["fov_deg"] if kw["fov_deg"] is not None else float(np.mean(kw["fov_range_deg"] or (5.0, 35.0)))
        return Camera.from_fov(data.shape[1], data.shape[0], fov)

    @property
    def mode(self) -> FrameMode:
        """The mode of the last image (:data:`POINT_MODE` or :data:`STREAK_MODE`)."""
        return self._mode

    def smear_limits(self, exposure_s: float, width: int, height: int) -> SmearLimits:
        """The smear diagnostics of an exposure (Samaan 2002 Table 1; module docstring), from the
        tracker's camera or, before it has one, a pinhole camera of its FOV for this image size."""
        from ..simulate import max_rate_rad_s

        camera = self._camera or self._nominal_camera(np.empty((int(height), int(width)), dtype=np.uint8))
        opt = self.options
        per_px = 1.0 / (camera.fx * exposure_s)  # rad/s across the boresight per pixel of smear
        return SmearLimits(exposure_s=float(exposure_s), pixel_arcsec=camera.pixel_scale_arcsec,
                           max_rate_deg_s=math.degrees(max_rate_rad_s(camera, exposure_s, 0.1)),
                           streak_on_px=opt.streak_on_px, streak_on_deg_s=math.degrees(opt.streak_on_px * per_px),
                           streak_off_px=opt.streak_off_px, streak_off_deg_s=math.degrees(opt.streak_off_px * per_px))

    def _streak_image(self, data: NDArray, t_s: float, exposure_s: float) -> TrackStep:
        """Streak processing: tracking from the prediction, else lost-in-space on the streaks."""
        t0 = time.perf_counter()
        solution = self._streak_tracked(data, t_s, exposure_s) if self._rot is not None and \
            self._camera is not None and self._rate is not None else None
        mode: StepMode = STREAK_TRACKING
        if solution is None or not solution.solved:
            solution, mode = self._streak_lost(data, exposure_s), STREAK_LOST_IN_SPACE
        if not solution.solved:
            return TrackStep(t_s, mode, solution.status, solution.reason, time_s=time.perf_counter() - t0)
        self._take_streak(solution, t_s)
        extra = {"rate_status": solution.rate.status.name, "n_streaks": solution.n_streaks,
                 "t_mid_s": solution.t_mid_s, "time_order_known": solution.time_order_known}
        scale = require(solution.camera, "the solution's camera").pixel_scale_arcsec
        rms = float(np.sqrt(np.mean(solution.residuals_arcsec**2)) / scale)
        return TrackStep(t_s, mode, Status.OK, "", solution.rot_cam_from_icrs, self._rate_copy(), solution.n_streaks,
                         rms, extra=extra)

    def _streak_options(self):
        from ..rate import StreakOptions

        return self.options.streak or StreakOptions()

    def _streak_tracked(self, data: NDArray, t_s: float, exposure_s: float):
        """The frame's streaks predicted from the last attitude and rate (either sign when the
        rate's time order is not known yet)."""
        from ..rate import prediction_slack_px, track_streaks

        dt = t_s - self._last_t
        memory = self._streak_memory
        signs = (1.0,) if memory.get("order_known", True) else (1.0, -1.0)
        solution = None
        rate = require(self._rate, "the rate of the last frames")
        for sign in signs:
            omega = sign * rate
            rot = Rotation.from_quat(quat_product(rotvec_quat(-omega * dt), self._last_quat))
            camera = self._known_camera
            slack = prediction_slack_px(camera, omega, dt, self.options.rate_error_fraction, 2.0)
            solution = track_streaks(data, camera, rot, omega, exposure_s, epoch_jyear=epoch_jyear(self._epoch),
                                     slack_px=slack, options=self._streak_options(),
                                     zero_point=memory.get("zero_point", 0.0), blur_px=memory.get("blur_px", 1.0),
                                     shot=memory.get("shot"))
            if solution.solved:
                memory["order_known"] = True
                break
        return solution

    def _streak_lost(self, data: NDArray, exposure_s: float):
        """Lost-in-space on the streaks (the tracker's rate, if any, orders the exposure in time)."""
        from ..rate import solve_streaked

        kwargs = {"camera": self._camera} if self._camera is not None else \
            {"fov_deg": self._lis_kwargs["fov_deg"], "fov_range_deg": self._lis_kwargs["fov_range_deg"]}
        return solve_streaked(data, exposure_s=exposure_s, epoch=self._epoch, prior_omega_rad_s=self._rate,
                              options=self._streak_options(), **kwargs)

    def _take_streak(self, solution, t_s: float) -> None:
        """Adopt a streak solution: its attitude, and its rate when it is trusted (else the rate
        from the attitudes, as in point mode); remember the frame's photometry for the next one."""
        from ..rate import v_mags, zero_point

        self._camera = self._camera or solution.camera
        fits, rows = solution.streaks, solution.streak_index
        self._streak_memory.update(blur_px=float(np.median(fits.blur_px[rows])), shot=fits.shot,
                                   zero_point=zero_point(fits.flux[rows], v_mags(solution.matches.hip)))
        differenced = self._quat is not None and self._t is not None and t_s > self._t
        self._advance(solution.rot_cam_from_icrs, t_s)
        known = solution.time_order_known or differenced
        if solution.rate.ok or usable_for_prediction(solution):
            omega = solution.turn_rad / solution.exposure_s
            if (not solution.time_order_known and differenced and self._rate is not None
                    and np.dot(omega, self._rate) < 0):
                omega = -omega  # the attitudes of two frames tell the time order one frame cannot
            self._rate = omega
        self._streak_memory["order_known"] = known

    def update_rig(self, stars, t_s: float, *, gyro_rate_rad_s: ArrayLike | None = None):
        """Process one frame of a rig: head name to ``(x, y)`` or ``(x, y, flux)`` star arrays, taken
        at ``t_s`` (s); ``gyro_rate_rad_s`` in the body frame. Returns a
        :class:`startrack.multihead._tracking.RigTrackStep` (``heads``: those that contributed)."""
        if self._rig is None:
            raise InvalidInputError("this Tracker follows one camera: build it with Tracker(rig=...) for a rig")
        return self._rig.update(stars, t_s, gyro_rate_rad_s=gyro_rate_rad_s)

    def reset(self) -> None:
        """Forget the attitude and rate (the next frame is solved lost-in-space)."""
        self._rot, self._quat, self._t, self._rate = None, None, None, None
        self._last_measured = None
        self._streak_memory = {}
        if self._rig is not None:
            self._rig.reset()

    # --- modes ----------------------------------------------------------------------------------
    @property
    def _last_t(self) -> float:
        return require(self._t, "the time of the last attitude")

    @property
    def _last_quat(self) -> Quat:
        return require(self._quat, "the last attitude")

    @property
    def _known_camera(self) -> Camera:
        return require(self._camera, "the tracker's camera (given, or fitted by the first solve)")

    def _window_px(self, dt: float) -> float:
        opt = self.options
        if self._rate is None:
            motion = math.radians(opt.max_rate_deg_s) * abs(dt)
        else:
            motion = opt.rate_error_fraction * math.hypot(*self._rate.tolist()) * abs(dt)
        return opt.window_px + motion * self._known_camera.fx

    def _window_matcher(self) -> WindowMatcher:
        """The matcher of the current camera and catalog limit (it keeps the stars near the boresight)."""
        stars = field_stars(self.options.catalog_max_mag, epoch_jyear(self._epoch))
        if self._matcher is None or self._matcher.camera is not self._camera or self._matcher.stars is not stars:
            self._matcher = WindowMatcher(self._known_camera, stars)
        return self._matcher

    def _predicted_quat(self, dt: float) -> Quat:
        """The attitude turned by the rate for ``dt`` seconds: ``exp(-[omega x] dt) A`` (camera-frame omega)."""
        if self._rate is None:
            return self._last_quat
        return quat_product(rotvec_quat(-self._rate * dt), self._last_quat)

    def _track(self, x: NDArray, y: NDArray, t_s: float) -> TrackStep | None:
        opt = self.options
        dt = t_s - self._last_t
        found = self._window_matcher().match(x, y, quat_matrix(self._predicted_quat(dt)),
                                             window_px=self._window_px(dt), match_px=opt.match_px,
                                             min_stars=opt.min_stars)
        if found.rot_cam_from_icrs is None or not found.residual_rms_px <= opt.max_residual_px:
            return None
        self._advance(found.rot_cam_from_icrs, t_s)
        return TrackStep(t_s, TRACKING, Status.OK, "", found.rot_cam_from_icrs, self._rate_copy(),
                         int(found.image_index.size), found.residual_rms_px)

    def _lost_in_space(self, x: NDArray, y: NDArray, t_s: float) -> TrackStep:
        kwargs = {"camera": self._camera, "epoch": self._epoch} if self._camera is not None else self._lis_kwargs
        solution = solve_stars(x, y, **kwargs)
        if not solution.solved:
            self.reset()
            return TrackStep(t_s, LOST_IN_SPACE, solution.status, solution.reason)
        self._camera = self._camera or solution.camera  # with the fitted focal length (and k1)
        self._advance(solution.rot_cam_from_icrs, t_s)
        scale = require(solution.camera, "the solution's camera").pixel_scale_arcsec
        rms = float(np.sqrt(np.mean(solution.residuals_arcsec**2)) / scale)
        return TrackStep(t_s, LOST_IN_SPACE, Status.OK, "", solution.rot_cam_from_icrs, self._rate_copy(),
                         len(solution.matches), rms)

    # --- state ----------------------------------------------------------------------------------
    def _advance(self, rot: Rotation, t_s: float) -> None:
        """Take a new attitude; update the smoothed rate from the previous one (if any).

        The measured rate is ``-rotvec(A_new A_old^T) / dt``, the exact log map of
        :func:`startrack.rate._from_attitudes.rate_between`.
        """
        quat = tuple(rot.as_quat().tolist())
        if self._quat is not None and self._t is not None and t_s > self._t:
            measured = -quat_rotvec(quat_product(quat, quat_conjugate(self._quat))) / (t_s - self._t)
            self._last_measured = measured
            gain = self.options.rate_gain
            self._rate = measured if self._rate is None else (1 - gain) * self._rate + gain * measured
        self._rot, self._quat, self._t = rot, quat, t_s

    def _rate_copy(self) -> NDArray | None:
        return None if self._rate is None else self._rate.copy()


def _with_time(step: TrackStep, seconds: float) -> TrackStep:
    return replace(step, time_s=seconds)
