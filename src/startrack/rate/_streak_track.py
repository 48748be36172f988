"""Streak mode while tracking: the previous frame's attitude and rate predict every streak of the
new frame, which is fitted in a window around its prediction only (Samaan 2002 Eq. 1–3 step 4 with the
smear of §"The Effect of Image Smear"; no segmentation, no lost-in-space).

1. The brightest ``lis_streaks`` catalog stars of the predicted field (by their expected light
   when the frame's zero point is known) are fitted from their predicted arcs in windows widened
   by the prediction's uncertainty (two passes, :func:`.streak_predict.fit_predicted`), and those
   that agree with the prediction give a first joint fit (:mod:`._streak_model`).
2. The other stars of the field are predicted from that fit and added as after a lost-in-space
   solve (:func:`.streak_solve.extend`), and the joint fit is done again.

The result is a :class:`.streak_solve.StreakSolution` (status TOO_FEW_STARS when fewer than
``min_streaks`` predicted streaks are found: the caller falls back to lost-in-space).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..identify import field_stars
from ..results import Status
from ._streak_find import robust_level
from ._streak_fit import fit_pixels
from ._streak_model import Timing, fit_joint
from ._streak_predict import Field, Identified, fit_predicted
from ._streak_solve import Stages, StreakOptions, StreakSolution, extend, failed_solution, streak_solution


def track_streaks(
    image: ArrayLike,
    camera: Camera,
    rot_mid: Rotation,
    omega_rad_s: ArrayLike,
    exposure_s: float,
    *,
    epoch_jyear: float,
    slack_px: float,
    options: StreakOptions | None = None,
    zero_point: float = 0.0,
    blur_px: float = 1.0,
    shot: float | None = None,
) -> StreakSolution:
    """The attitude at mid-exposure and the rate of a streaked frame predicted by ``rot_mid``
    (``rot_cam_from_icrs`` at this frame's mid-exposure) and ``omega_rad_s`` (module docstring).

    Parameters
    ----------
    image : array_like, shape (H, W)
    camera : Camera
        The calibrated camera (its focal length is not fitted).
    rot_mid, omega_rad_s : Rotation, array_like (3,)
        The prediction (camera frame, rad/s); the rate's sign orders the exposure in time.
    exposure_s : float
    epoch_jyear : float
        Catalog epoch.
    slack_px : float
        How far (px) the predicted streaks may be from the real ones: the first windows are
        widened by it.
    options : StreakOptions, optional
    zero_point, blur_px, shot : float
        The frame's light of a V = 0 star (0: unknown: the brightest catalog stars are tried),
        blur (px) and photon-noise factor (None: estimated), as the previous frame found them.
    """
    opts = options or StreakOptions()
    img = np.asarray(image)
    clock = Stages()
    timing = Timing(float(exposure_s), opts.line_time_s, img.shape[0])
    omega = np.asarray(omega_rad_s, dtype=float)
    background, noise = robust_level(img)
    field = Field.around(field_stars(opts.catalog_max_mag, epoch_jyear), camera, rot_mid,
                         float(np.linalg.norm(omega)) * timing.exposure_s)
    pixels, saturation = fit_pixels(img)
    index, fits = fit_predicted(pixels, camera, field.vectors, rot_mid, omega, np.zeros(3), timing, noise=noise,
                                background=background, blur_px=blur_px, shot=shot, slack_px=slack_px,
                                tolerance_px=slack_px + 3.0, limit=opts.lis_streaks, flux=field.flux(zero_point),
                                passes=2, saturation=saturation)
    clock.mark("fit")
    if fits is None or fits.ok.sum() < opts.min_streaks:
        n_found = 0 if fits is None else int(fits.ok.sum())
        return failed_solution(Status.TOO_FEW_STARS, f"{n_found} predicted streaks found ({opts.min_streaks} needed)",
                       fits if fits is not None else _no_fits(noise, background), timing, clock)
    ok = np.flatnonzero(fits.ok)
    found = Identified(fits, ok, field.vectors[index[ok]], field.hips[index[ok]])
    measured, cov = found.measurements()
    joint = fit_joint(camera, found.stars, measured, cov, rot_mid, omega, timing, fit_alpha=opts.fit_alpha)
    clock.mark("joint")
    found, joint = extend(pixels, found, joint, timing, field, noise=noise, background=background, opts=opts,
                          fit_focal=False, saturation=saturation)
    clock.mark("predicted")
    return streak_solution(found, joint, timing, opts, omega, exposure_s, clock, epoch_jyear=epoch_jyear,
                           epoch_source="given")


def _no_fits(noise: float, background: float):
    from ._streak_fit import NPAR, StreakFits

    empty = np.zeros(0)
    return StreakFits(np.zeros((0, NPAR)), np.zeros((0, NPAR, NPAR)), empty, np.zeros(0, dtype=np.int64),
                      np.zeros(0, dtype=bool), (), np.zeros(0, dtype=np.int32), 0.0, noise, background)


def prediction_slack_px(camera: Camera, omega_rad_s: NDArray, dt_s: float, rate_error_fraction: float,
                        window_px: float) -> float:
    """How far (px) streaks predicted ``dt_s`` ahead with a rate known to ``rate_error_fraction``
    may lie from the real ones: the rate's error times the interval, plus ``window_px``."""
    return window_px + rate_error_fraction * float(np.linalg.norm(omega_rad_s)) * abs(dt_s) * camera.fx
