"""Tracking with a rig: every head's windows predicted from the joint attitude and rate (Samaan 2002
§2.2, per field of view), one joint fit, lost-in-space (:func:`.solve.solve_rig`) when it fails.

Each frame, the body attitude is turned by the body-frame rate (a gyro's, or the smoothed
frame-to-frame rate) to the frame's time; every head's catalog stars are predicted through its
mounting and matched within a window (:attr:`startrack.track.TrackerOptions.window_px` plus the
motion the rate's uncertainty allows, at that head's focal length), the joint attitude is fitted
over all matched stars of all heads (:mod:`._joint`), the stars matched again within
``match_px`` and the attitude refitted. The frame is tracked while at least one head matches
``min_stars`` stars and the residuals stay under ``max_residual_px``; heads with fewer matches
still contribute their stars. :class:`RigTrackStep` says which heads contributed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError, check_instance, require
from ..identify import field_stars
from ..results import Status
from ..rig import CameraRig
from ..solve import epoch_jyear
from ..track import LOST_IN_SPACE, TRACKING, TrackerOptions, WindowMatcher, checked_rate, checked_time
from ._joint import fit_joint, measured_sigma_px, residuals_px
from ._predict import head_matcher, match_predicted
from ._solution import RigOptions, RigSolution
from ._solve import solve_head_stars
from ._stars import HeadStars, rig_stars


@dataclass(frozen=True)
class RigTrackStep:
    """What the rig tracker made of one frame.

    Attributes
    ----------
    t_s : float
    mode : str
        "tracking" or "lost-in-space".
    status : Status
    reason : str
    rot_body_from_icrs : Rotation or None
    rate_body_rad_s : ndarray, shape (3,) or None
        Smoothed body-frame rate (rad/s) after this frame.
    heads : tuple of str
        Heads whose stars are in the frame's attitude.
    n_matched : dict of str to int
        Stars matched per head.
    residual_rms_px : float
        Rms pixel residual over all matched stars.
    time_s : float
    solution : RigSolution or None
        The lost-in-space solution, for a frame solved that way.
    """

    t_s: float
    mode: str
    status: Status
    reason: str = ""
    rot_body_from_icrs: Rotation | None = None
    rate_body_rad_s: NDArray[np.float64] | None = None
    heads: tuple[str, ...] = ()
    n_matched: dict[str, int] = field(default_factory=dict)
    residual_rms_px: float = float("nan")
    time_s: float = 0.0
    solution: RigSolution | None = None


class RigTracker:
    """Follows a rig's body attitude over a sequence of frames of star lists (module docstring).

    Parameters
    ----------
    rig : CameraRig
    epoch : float or astropy Time, optional
        Catalog epoch; default J2000.0.
    options : TrackerOptions, optional
        The single-camera tracker's settings, applied per head.
    rig_options : RigOptions, optional
        Settings of the lost-in-space rig solve.
    """

    def __init__(self, rig: CameraRig, *, epoch=None, options: TrackerOptions | None = None,
                 rig_options: RigOptions | None = None):
        if not isinstance(rig, CameraRig):
            raise InvalidInputError(f"rig must be a CameraRig, got {type(rig).__name__}")
        self.rig = rig
        self.options = TrackerOptions() if options is None else check_instance(options, TrackerOptions,
                                                                                 "options of the RigTracker")
        self.rig_options = RigOptions(catalog_max_mag=self.options.catalog_max_mag) if rig_options is None else \
            check_instance(rig_options, RigOptions, "rig_options of the RigTracker")
        self._epoch = epoch_jyear(epoch)
        catalog = field_stars(self.options.catalog_max_mag, self._epoch)
        self._matchers: dict[str, WindowMatcher] = {h.name: head_matcher(h, catalog) for h in rig}
        self.reset()

    def reset(self) -> None:
        """Forget the attitude and rate (the next frame is solved lost-in-space)."""
        self._rot: Rotation | None = None
        self._t: float | None = None
        self._rate: NDArray | None = None

    def update(self, stars: Mapping[str, tuple], t_s: float, *,
               gyro_rate_rad_s: ArrayLike | None = None) -> RigTrackStep:
        """Process one frame: head name to ``(x, y)`` or ``(x, y, flux)`` (as :func:`startrack.solve_rig`),
        taken at ``t_s`` (s); ``gyro_rate_rad_s`` is a body-frame rate (rad/s).

        Every input is checked before the tracker's state changes: a non-finite time or rate, or
        a bad star list, raises InvalidInputError (as :meth:`startrack.track.Tracker.update`) and
        leaves the attitude and rate as they were."""
        t0 = time.perf_counter()
        t_s = checked_time(t_s)
        lists = rig_stars(stars, self.rig)
        if gyro_rate_rad_s is not None:
            self._rate = checked_rate(gyro_rate_rad_s, "body")
        step = self._track(lists, t_s) if self._rot is not None else None
        if step is None:
            step = self._lost_in_space(lists, t_s)
        return replace(step, time_s=time.perf_counter() - t0)

    # --- modes --------------------------------------------------------------------------------
    def _window_px(self, dt: float, fx: float) -> float:
        opt = self.options
        if self._rate is None:
            motion = math.radians(opt.max_rate_deg_s) * abs(dt)
        else:
            motion = opt.rate_error_fraction * float(np.linalg.norm(self._rate)) * abs(dt)
        return opt.window_px + motion * fx

    def _predicted(self, dt: float) -> Rotation:
        """The body attitude turned by the body-frame rate for ``dt`` s: ``exp(-[omega x] dt) A``."""
        if self._rate is None:
            return self._rot
        return Rotation.from_rotvec(-self._rate * dt) * self._rot

    def _track(self, lists: dict[str, HeadStars], t_s: float) -> RigTrackStep | None:
        opt = self.options
        dt = t_s - require(self._t, "the time of the last tracked frame")
        rot = self._predicted(dt)
        radius = {n: self._window_px(dt, s.head.camera.fx) for n, s in lists.items()}
        sigma = {n: s.head.centroid_sigma_px for n, s in lists.items()}
        for _ in range(2):
            matches = {n: match_predicted(s, self._matchers[n], rot, radius[n])[0] for n, s in lists.items()}
            fit = fit_joint(list(matches.values()), sigma)
            if fit is None or max(len(m) for m in matches.values()) < opt.min_stars:
                return None
            rot = fit.rot_body_from_icrs
            radius = {n: opt.match_px for n in lists}
            sigma = {n: measured_sigma_px(m, m.stars.head.rot_cam_from_icrs(rot), 0.05) for n, m in matches.items()}
        rms = _rms_px(matches.values(), rot)
        if not rms <= opt.max_residual_px:
            return None
        self._advance(rot, t_s)
        return RigTrackStep(t_s, TRACKING, Status.OK, "", rot, self._rate_copy(),
                            tuple(n for n, m in matches.items() if len(m)), {n: len(m) for n, m in matches.items()},
                            rms)

    def _lost_in_space(self, lists: dict[str, HeadStars], t_s: float) -> RigTrackStep:
        solution = solve_head_stars(lists, self.rig, self._epoch, "quads", self.rig_options)
        if not solution.solved:
            self.reset()
            return RigTrackStep(t_s, LOST_IN_SPACE, solution.status, solution.reason, solution=solution)
        self._advance(solution.rot_body_from_icrs, t_s)
        rms = float(np.sqrt(np.mean(np.concatenate([r for r in solution.residuals_arcsec.values()]) ** 2)))
        scale = self.rig.head(solution.heads_used[0]).camera.pixel_scale_arcsec
        return RigTrackStep(t_s, LOST_IN_SPACE, Status.OK, "", solution.rot_body_from_icrs, self._rate_copy(),
                            solution.heads_used, {n: len(m) for n, m in solution.matches.items()}, rms / scale,
                            solution=solution)

    # --- state --------------------------------------------------------------------------------
    def _advance(self, rot: Rotation, t_s: float) -> None:
        """Take a new attitude; update the smoothed body rate, ``-rotvec(A_new A_old^T) / dt``."""
        if self._rot is not None and self._t is not None and t_s > self._t:
            measured = -(rot * self._rot.inv()).as_rotvec() / (t_s - self._t)
            gain = self.options.rate_gain
            self._rate = measured if self._rate is None else (1 - gain) * self._rate + gain * measured
        self._rot, self._t = rot, t_s

    def _rate_copy(self) -> NDArray | None:
        return None if self._rate is None else self._rate.copy()


def _rms_px(matches, rot: Rotation) -> float:
    """Rms pixel residual over the matched stars of all heads."""
    parts = [residuals_px(m, m.stars.head.rot_cam_from_icrs(rot)) for m in matches if len(m)]
    d = np.concatenate(parts) if parts else np.zeros((0, 2))
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1)))) if len(d) else float("nan")


__all__ = ["RigTrackStep", "RigTracker"]
