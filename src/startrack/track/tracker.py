"""The Tracker: a state machine over a sequence of frames (DESIGN.md §1; seed 000 §1.33 mode
logic, seed 004 §2.2 predictive loop, seed 002 §4 tracking).

* No attitude yet (or tracking just failed): lost-in-space (:func:`startrack.solve_stars`).
* An attitude from the previous frame: predict this frame's attitude with the rate (from a gyro
  when given, otherwise from the last two attitudes, smoothed), identify stars in windows around
  their predicted positions (:func:`.windows.match_in_windows`), confirm with the geometry of the
  matched stars (enough stars, residuals at the noise level). If that fails, fall back to
  lost-in-space in the same frame.

A lost-in-space solve with an unknown FOV fixes the camera (its fitted focal length) for the
frames after it.

Given a :class:`startrack.CameraRig` (``Tracker(rig=...)``), the tracker follows the rig's body
attitude with :meth:`Tracker.update_rig` (:class:`startrack.multihead.tracking.RigTracker`): every
head's windows predicted from the joint attitude and rate, tracking while at least one head sees
``min_stars`` stars, and each step says which heads contributed.

A tracking step keeps its attitude as a quaternion and predicts, fits and differences attitudes
with :mod:`.quaternions` (the same kinematics as :func:`startrack.attitude.propagation.propagate`
and :func:`startrack.rate.from_attitudes.rate_between`, without scipy's per-call overhead); the
catalog stars around the boresight are kept from frame to frame (:class:`.windows.WindowMatcher`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError
from ..frames import radec_roll_from_rotation
from ..identify.field_stars import field_stars
from ..results import Status
from ..solve import epoch_jyear, solve_stars
from .quaternions import Quat, quat_conjugate, quat_matrix, quat_product, quat_rotvec, rotvec_quat
from .windows import WindowMatcher

LOST_IN_SPACE = "lost-in-space"
TRACKING = "tracking"


@dataclass(frozen=True)
class TrackerOptions:
    """Settings of the Tracker.

    Attributes
    ----------
    min_stars : int
        Fewest matched stars for a tracked attitude.
    window_px : float
        Search half-window around each predicted star when the rate is known.
    max_rate_deg_s : float
        Largest rate expected; sets the window when the rate is not known yet.
    rate_error_fraction : float
        Assumed relative error of the rate estimate; widens the window with the motion.
    match_px : float
        Match radius once the attitude is refitted to the window matches.
    max_residual_px : float
        A tracked attitude whose matched stars leave a larger rms residual is rejected.
    rate_gain : float
        Weight of the newest frame-to-frame rate in the smoothed rate (0 < gain <= 1).
    catalog_max_mag : float
        Faintest catalog star predicted (V).
    target_stars : int or None
        For :meth:`Tracker.update_image`: detect with the dynamic threshold aiming at this many
        stars (None: the detector's default k-sigma threshold).
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


@dataclass(frozen=True)
class TrackStep:
    """What the Tracker made of one frame."""

    t_s: float
    mode: str
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
        return tuple(float(np.degrees(a)) for a in radec_roll_from_rotation(self.rot_cam_from_icrs))


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
                 fov_deg: float | None = None, fov_range_deg: tuple[float, float] | None = None, epoch=None,
                 options: TrackerOptions | None = None, rig=None):
        self._rig = None
        if rig is not None:
            if any(v is not None for v in (camera, width, height, fov_deg, fov_range_deg)):
                raise InvalidInputError("a rig has its cameras: give rig, or a camera (or size and FOV), not both")
            from ..multihead.tracking import RigTracker  # the rig mode builds on this module

            self._rig = RigTracker(rig, epoch=epoch, options=options)
        elif camera is None and (width is None or height is None):
            raise InvalidInputError("give a camera, or the image width and height (and a FOV or FOV range)")
        self.options = options or TrackerOptions()
        self._lis_kwargs = {"width": width, "height": height, "fov_deg": fov_deg, "fov_range_deg": fov_range_deg,
                            "epoch": epoch}
        self._camera = camera
        self._rot: Rotation | None = None
        self._quat: Quat | None = None
        self._t: float | None = None
        self._rate: NDArray | None = None
        self._epoch = epoch
        self._matcher: WindowMatcher | None = None

    # --- public ---------------------------------------------------------------------------------
    def update(self, x: ArrayLike, y: ArrayLike, t_s: float, *, flux: ArrayLike | None = None,
               gyro_rate_rad_s: ArrayLike | None = None) -> TrackStep:
        """Process one frame's star list (our pixel convention) taken at time ``t_s`` (seconds)."""
        if self._rig is not None:
            raise InvalidInputError("this Tracker follows a rig: give each head's stars to update_rig")
        t0 = time.perf_counter()
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        if flux is not None:
            order = np.argsort(-np.asarray(flux, dtype=float), kind="stable")
            x, y = x[order], y[order]
        if gyro_rate_rad_s is not None:
            self._rate = _checked_rate(gyro_rate_rad_s)
        step = self._track(x, y, t_s) if self._rot is not None and self._camera is not None else None
        if step is None:
            step = self._lost_in_space(x, y, t_s)
        return _with_time(step, time.perf_counter() - t0)

    def update_image(self, image, t_s: float, *, detector=None, gyro_rate_rad_s=None,
                     streak_exposure_s: float | None = None, streak_bias_px: float = 0.0) -> TrackStep:
        """Detect the stars of an image (array or path) and :meth:`update` with them.

        With ``streak_exposure_s`` (s) and a known camera, a streaked image (``choose_mode``)
        gives its own rate (:func:`startrack.rate.streak_rate.streak_rate` with Harris endpoints,
        which take a fraction of a second where the fitted segments of the default can take
        seconds on long streaks; ends corrected by ``streak_bias_px``; a rate its consistency
        checks refuse is not used), ordered in time by ``gyro_rate_rad_s`` or
        the tracker's rate; it replaces the gyro rate for this frame. Without an order, or if it
        fails, the gyro rate (if any) is used.

        Without a ``detector``, stars are detected with :attr:`TrackerOptions.target_stars`:
        None uses the default k-sigma threshold, a number the dynamic threshold that adapts to
        reach that many stars (seed 000 §8.2.3).
        """
        from ..detect import StarDetector
        from ..io import read_image

        data = read_image(image).data
        if streak_exposure_s is not None:
            gyro_rate_rad_s = self._streak_rate(data, streak_exposure_s, streak_bias_px, gyro_rate_rad_s)
        if detector is None:
            target = self.options.target_stars
            detector = StarDetector() if target is None else StarDetector(threshold="dynamic", target_stars=target)
        found = detector.detect(data)
        return self.update(found.x, found.y, t_s, gyro_rate_rad_s=gyro_rate_rad_s)

    def _streak_rate(self, data: NDArray, exposure_s: float, bias_px: float, gyro_rate_rad_s) -> NDArray | None:
        """The rate of a streaked frame (time-ordered by the gyro or tracker rate), else the gyro's."""
        from ..rate.streak_rate import choose_mode, streak_rate

        prior = gyro_rate_rad_s if gyro_rate_rad_s is not None else self._rate
        if self._camera is None or prior is None or choose_mode(data).mode != "streak":
            return gyro_rate_rad_s
        found = streak_rate(data, self._camera, exposure_s, detector="harris", bias_px=bias_px,
                            prior_omega_rad_s=prior)
        return found.rate.omega_rad_s if found.rate.ok and found.time_order_known else gyro_rate_rad_s

    def update_rig(self, stars, t_s: float, *, gyro_rate_rad_s: ArrayLike | None = None):
        """Process one frame of a rig: head name to ``(x, y)`` or ``(x, y, flux)`` star arrays, taken
        at ``t_s`` (s); ``gyro_rate_rad_s`` in the body frame. Returns a
        :class:`startrack.multihead.tracking.RigTrackStep` (``heads``: those that contributed)."""
        if self._rig is None:
            raise InvalidInputError("this Tracker follows one camera: build it with Tracker(rig=...) for a rig")
        return self._rig.update(stars, t_s, gyro_rate_rad_s=gyro_rate_rad_s)

    def reset(self) -> None:
        """Forget the attitude and rate (the next frame is solved lost-in-space)."""
        self._rot, self._quat, self._t, self._rate = None, None, None, None
        if self._rig is not None:
            self._rig.reset()

    # --- modes ----------------------------------------------------------------------------------
    def _window_px(self, dt: float) -> float:
        opt = self.options
        if self._rate is None:
            motion = math.radians(opt.max_rate_deg_s) * abs(dt)
        else:
            motion = opt.rate_error_fraction * math.hypot(*self._rate.tolist()) * abs(dt)
        return opt.window_px + motion * self._camera.fx

    def _window_matcher(self) -> WindowMatcher:
        """The matcher of the current camera and catalog limit (it keeps the stars near the boresight)."""
        stars = field_stars(self.options.catalog_max_mag, epoch_jyear(self._epoch))
        if self._matcher is None or self._matcher.camera is not self._camera or self._matcher.stars is not stars:
            self._matcher = WindowMatcher(self._camera, stars)
        return self._matcher

    def _predicted_quat(self, dt: float) -> Quat:
        """The attitude turned by the rate for ``dt`` seconds: ``exp(-[omega x] dt) A`` (camera-frame omega)."""
        if self._rate is None:
            return self._quat
        return quat_product(rotvec_quat(-self._rate * dt), self._quat)

    def _track(self, x: NDArray, y: NDArray, t_s: float) -> TrackStep | None:
        opt = self.options
        dt = t_s - self._t
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
        rms = float(np.sqrt(np.mean(solution.residuals_arcsec**2)) / solution.camera.pixel_scale_arcsec)
        return TrackStep(t_s, LOST_IN_SPACE, Status.OK, "", solution.rot_cam_from_icrs, self._rate_copy(),
                         len(solution.matches), rms)

    # --- state ----------------------------------------------------------------------------------
    def _advance(self, rot: Rotation, t_s: float) -> None:
        """Take a new attitude; update the smoothed rate from the previous one (if any).

        The measured rate is ``-rotvec(A_new A_old^T) / dt``, the exact log map of
        :func:`startrack.rate.from_attitudes.rate_between`.
        """
        quat = tuple(rot.as_quat().tolist())
        if self._quat is not None and self._t is not None and t_s > self._t:
            measured = -quat_rotvec(quat_product(quat, quat_conjugate(self._quat))) / (t_s - self._t)
            gain = self.options.rate_gain
            self._rate = measured if self._rate is None else (1 - gain) * self._rate + gain * measured
        self._rot, self._quat, self._t = rot, quat, t_s

    def _rate_copy(self) -> NDArray | None:
        return None if self._rate is None else self._rate.copy()


def _checked_rate(rate_rad_s: ArrayLike) -> NDArray[np.float64]:
    rate = np.array(rate_rad_s, dtype=float)
    if rate.shape != (3,) or not np.all(np.isfinite(rate)):
        raise InvalidInputError(f"gyro_rate_rad_s must be 3 finite numbers (rad/s, camera frame), got {rate_rad_s!r}")
    return rate


def _with_time(step: TrackStep, seconds: float) -> TrackStep:
    return replace(step, time_s=seconds)
