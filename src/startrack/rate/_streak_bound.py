"""What a streaked frame's identified streaks allow: the Cramér-Rao bound of its rate, and the
chance that an efficient unbiased estimator meets a rate target with them.

Issue 19 asks that every frame with five identified streaks give a rate within 1 % and an
axis within 0.5 deg. Whether a frame can is a property of its streaks (how many, how long, how
far from the boresight, how precisely their ends are measured), not of the solver: this module
evaluates the information of the joint fit (:func:`._streak_model.information_covariance`) at
the true state, with the covariances the streak fits measured, so that a benchmark can set each
frame's result beside what its streaks permit.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ._streak_model import Timing, information_covariance
from ._streak_solve import StreakSolution

CHANCE_DRAWS = 4000
"""Gaussian draws of :func:`target_chance` (its standard error is at most 0.8 % of a share)."""


def rate_bound(solution: StreakSolution, camera: Camera, rot_mid: Rotation, omega_rad_s: ArrayLike,
               alpha_rad_s2: ArrayLike | None = None, *, fit_alpha: bool = False,
               fit_focal: bool = True) -> NDArray[np.float64]:
    """Cramér-Rao covariance (3, 3) of the rate (rad^2/s^2, camera frame) that the streaks of a
    solved frame's joint fit allow at the true state.

    Parameters
    ----------
    solution : StreakSolution
        A solved streak frame: its joint fit's streaks (``streak_index`` into ``streaks``), their
        stars (``matches.cat_vectors``, ICRS), exposure and line time.
    camera : Camera
        The true camera.
    rot_mid : Rotation
        The true attitude at mid-exposure (camera from ICRS).
    omega_rad_s, alpha_rad_s2 : array_like, shape (3,)
        The true rate (rad/s) and angular acceleration (rad/s^2; default zero), camera frame.
    fit_alpha, fit_focal : bool
        What the fit also estimates (nuisance parameters widen the bound): the acceleration,
        the focal length (True when the solver was given a field of view, not a camera).

    Returns
    -------
    ndarray, shape (3, 3)
        NaN when the frame is not solved or its exposure is unknown.
    """
    fits = solution.streaks
    if not solution.solved or fits is None or not math.isfinite(solution.exposure_s) or solution.n_streaks < 3:
        return np.full((3, 3), np.nan)
    cov = fits.measurements()[1][solution.streak_index]
    timing = Timing(solution.exposure_s, solution.line_time_s, camera.height)
    alpha = np.zeros(3) if alpha_rad_s2 is None else alpha_rad_s2
    full = information_covariance(camera, solution.matches.cat_vectors, cov, rot_mid, omega_rad_s, alpha, timing,
                                  fit_alpha=fit_alpha, fit_focal=fit_focal)
    return full[3:6, 3:6]


def target_chance(cov: ArrayLike, omega_rad_s: ArrayLike, rate_fraction: float, axis_rad: float,
                  seed: int = 0) -> float:
    """Chance that a rate estimate with Gaussian error of covariance ``cov`` (3, 3; rad^2/s^2)
    about the true ``omega_rad_s`` (3,) is within ``rate_fraction`` of |omega| and within
    ``axis_rad`` of its axis: the share of :data:`CHANCE_DRAWS` draws (a fixed ``seed``, so the
    same inputs give the same number). NaN for a NaN covariance."""
    cov = np.asarray(cov, dtype=float)
    omega = np.asarray(omega_rad_s, dtype=float)
    if not np.all(np.isfinite(cov)):
        return math.nan
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    draws = np.random.default_rng(seed).standard_normal((CHANCE_DRAWS, 3)) * np.sqrt(np.maximum(values, 0.0))
    est = omega + draws @ vectors.T
    norm = float(np.linalg.norm(omega))
    within = np.linalg.norm(est - omega, axis=1) <= rate_fraction * norm
    axis = np.arctan2(np.linalg.norm(np.cross(est, omega), axis=1), est @ omega)
    return float(np.mean(within & (axis <= axis_rad)))
