"""Attitude at mid-exposure and body rate (and optionally a constant angular acceleration) fitted
jointly to every identified streak of a frame.

The forward model is the simulator's (:mod:`startrack.simulate._streaks`): over the exposure the
camera turns as ``rot(t) = exp(-[theta(t) x]) rot_mid`` with ``theta(t) = omega t + alpha t^2 / 2``
(camera frame, t from the frame's mid time), so a star of ICRS direction ``s`` is at camera
vector ``exp(-[theta(t) x]) rot_mid s``, projected by the camera (distortion included). Row y of
a rolling shutter integrates during ``[tau_y - T/2, tau_y + T/2]`` with
``tau_y = (y - (H - 1) / 2) line_time``, so the star's light lies on the image from the time
``t_a = tau_(y(t_a)) - T/2`` to ``t_b = tau_(y(t_b)) + T/2`` (found by iteration, as the
simulator does), uniformly in time. Each streak's measurement (:meth:`.streak_fit.StreakFits.
measurements`) is its two ends and its light centroid; the model predicts the star's positions at
``t_a`` and ``t_b`` and its mean position over ``[t_a, t_b]`` (5-point Gauss-Legendre). The
parameters (a small rotation of a first attitude, omega, alpha) minimise
``sum_i r_i^T C_i^-1 r_i`` over the streaks (Gauss-Newton with a numerical Jacobian, the fit of
each streak's pixels summarised by its ends and centroid with their covariance ``C_i``: the
issue's "equivalent fit to the fitted streak ends weighted by their covariance"). A streak
whose own chi-square is an outlier is dropped (an RSO, a crossing streak, a wrong match). Which of
a streak's two ends is the start is taken from the model; one frame does not tell the time
order (omega and -omega give the same image with a global shutter), so the caller orders it
with a prior rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ._streak_find import kernel

GAUSS_NODES, GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(5)
ROW_TIME_ITERATIONS = 3
MAX_ITERATIONS = 12
OUTLIER_CHI2 = 40.0
"""A streak whose chi-square (6 numbers) exceeds this is dropped (p ~ 1e-6 for a good one)."""
MODEL_FLOOR_PX = 0.02
"""Added in quadrature to every measured coordinate's sigma: what the fit's parabola and blur
model do not represent."""


@dataclass(frozen=True)
class Timing:
    """When the rows of a frame integrate: ``exposure_s``, the rolling-shutter ``line_time_s``
    (0: global shutter) and the number of rows ``height``."""

    exposure_s: float
    line_time_s: float = 0.0
    height: int = 1

    def row_mid_s(self, y: NDArray) -> NDArray[np.float64]:
        """Mid time of row y's integration from the frame's mid time, s."""
        return (np.asarray(y, dtype=float) - 0.5 * (self.height - 1)) * self.line_time_s

    @property
    def mid_after_start_s(self) -> float:
        """The frame's mid time after the start of row 0's integration."""
        return 0.5 * self.exposure_s + 0.5 * (self.height - 1) * self.line_time_s


def rotate(vectors: NDArray, theta: NDArray) -> NDArray[np.float64]:
    """``exp(-[theta x]) v`` for vectors (..., 3) and rotation vectors theta (..., 3), broadcast
    against each other (Rodrigues; compiled: :func:`._streak_kernel.rodrigues`)."""
    shape = np.broadcast_shapes(np.shape(vectors), np.shape(theta))
    v, th, out = np.empty(shape), np.empty(shape), np.empty(shape)
    v[...], th[...] = vectors, theta
    kernel().rodrigues(v.reshape(-1, 3), th.reshape(-1, 3), out.reshape(-1, 3))
    return out


def positions(camera: Camera, v_mid: NDArray, omega: NDArray, alpha: NDArray, t: NDArray,
              log_scale: NDArray | None = None) -> NDArray:
    """Pixel positions (B, N, m, 2) of camera vectors at mid time (B, N, 3) at times t (B, N, m),
    for B parameter sets omega, alpha (B, 3) and focal-length log-scales (B,) (0: the camera's)."""
    theta = omega[:, None, None, :] * t[..., None] + 0.5 * alpha[:, None, None, :] * t[..., None] ** 2
    v = rotate(v_mid[:, :, None, :], theta)
    x, y = camera.vector_to_pixel(v.reshape(-1, 3))
    xy = np.stack([x, y], axis=-1).reshape(t.shape + (2,))
    if log_scale is None or not np.any(log_scale):
        return xy
    centre = np.array([camera.cx, camera.cy])
    return centre + (xy - centre) * np.exp(log_scale)[:, None, None, None]


def end_times(camera: Camera, v_mid: NDArray, omega: NDArray, alpha: NDArray, timing: Timing,
              log_scale: NDArray | None = None) -> tuple[NDArray, NDArray]:
    """Times (B, N) at which each star's light starts and stops reaching its rows (module docstring)."""
    half = 0.5 * timing.exposure_s
    t = np.broadcast_to(np.array([-half, half]), v_mid.shape[:2] + (2,)).copy()
    if timing.line_time_s > 0:
        for _ in range(ROW_TIME_ITERATIONS):
            y = positions(camera, v_mid, omega, alpha, t, log_scale)[..., 1]
            t = timing.row_mid_s(y) + np.array([-half, half])
    return t[..., 0], t[..., 1]


def predict_batch(camera: Camera, v_mid: NDArray, omega: NDArray, alpha: NDArray, log_scale: NDArray,
                  timing: Timing) -> NDArray[np.float64]:
    """Predicted (start x, y, end x, y, light centroid x, y) (B, N, 6) of mid-time camera
    vectors (B, N, 3) under B parameter sets (omega, alpha (B, 3), log_scale (B,))."""
    ta, tb = end_times(camera, v_mid, omega, alpha, timing, log_scale)
    nodes = 0.5 * (ta + tb)[..., None] + 0.5 * (tb - ta)[..., None] * GAUSS_NODES
    times = np.concatenate([ta[..., None], tb[..., None], nodes], axis=-1)
    p = positions(camera, v_mid, omega, alpha, times, log_scale)
    centroid = 0.5 * np.einsum("k,bnkd->bnd", GAUSS_WEIGHTS, p[:, :, 2:])
    return np.concatenate([p[:, :, 0], p[:, :, 1], centroid], axis=-1)


def predict(camera: Camera, rot_mid: Rotation, omega: ArrayLike, alpha: ArrayLike, stars_icrs: NDArray,
            timing: Timing) -> NDArray[np.float64]:
    """Predicted (start x, y, end x, y, light centroid x, y) (N, 6) of stars (N, 3) (module docstring)."""
    v_mid = rot_mid.apply(stars_icrs).reshape(1, -1, 3)
    omega = np.asarray(omega, dtype=float).reshape(1, 3)
    alpha = np.asarray(alpha, dtype=float).reshape(1, 3)
    return predict_batch(camera, v_mid, omega, alpha, np.zeros(1), timing)[0]


def whitening(cov: NDArray, floor_px: float = MODEL_FLOOR_PX) -> NDArray[np.float64]:
    """W (K, 6, 6) with W^T W = (C + floor^2 I)^-1 for covariances C (K, 6, 6)."""
    values, vectors = np.linalg.eigh(cov + floor_px**2 * np.eye(6)[None])
    values = np.maximum(values, floor_px**2)
    return np.swapaxes(vectors, 1, 2) / np.sqrt(values)[:, :, None]


def ordered(measured: NDArray, predicted: NDArray, white: NDArray) -> NDArray[np.float64]:
    """The measurements (K, 6) with each streak's two ends in the order of the prediction."""
    swapped = measured[:, [2, 3, 0, 1, 4, 5]]
    direct = np.einsum("kij,kj->ki", white, measured - predicted)
    other = np.einsum("kij,kj->ki", white, swapped - predicted)
    flip = np.sum(other**2, axis=1) < np.sum(direct**2, axis=1)
    return np.where(flip[:, None], swapped, measured)


@dataclass(frozen=True)
class JointFit:
    """The attitude at mid-exposure, rate and acceleration fitted to K streaks.

    ``covariance`` (P, P) is of (attitude error rotvec, omega, alpha, ln focal length) (rad,
    rad/s, rad/s^2; camera frame; zero rows and columns for what was not fitted), scaled up by
    ``birge`` (the rms whitened residual per degree of freedom) when that exceeds 1; ``used``
    (K,) the streaks kept; ``chi2`` (K,) each streak's chi-square; ``measured`` (K, 6) the
    measurements in time order (start, end, centroid), ``predicted`` (K, 6) the model's;
    ``camera`` the camera with the fitted focal length.
    """

    rot_mid: Rotation
    omega_rad_s: NDArray[np.float64]
    alpha_rad_s2: NDArray[np.float64]
    covariance: NDArray[np.float64]
    used: NDArray[np.bool_]
    chi2: NDArray[np.float64]
    birge: float
    measured: NDArray[np.float64]
    predicted: NDArray[np.float64]
    camera: Camera

    @property
    def rate_covariance(self) -> NDArray[np.float64]:
        return self.covariance[3:6, 3:6]

    @property
    def attitude_covariance(self) -> NDArray[np.float64]:
        return self.covariance[0:3, 0:3]


@dataclass(frozen=True)
class _Problem:
    """What one joint fit holds fixed: the camera, the stars, the whitened measurements' parts."""

    camera: Camera
    v0: NDArray[np.float64]
    """The stars' camera vectors (K, 3) at the first-guess attitude ``rot0``."""
    white: NDArray[np.float64]
    rot0: Rotation
    timing: Timing
    free: NDArray[np.bool_]
    """Which of the 10 parameters (rotvec 3, omega 3, alpha 3, ln f) are fitted."""

    def full(self, q: NDArray) -> NDArray[np.float64]:
        """Parameter sets (B, P) as the 10 of every set (B, 10)."""
        out = np.zeros(q.shape[:-1] + (10,))
        out[..., self.free] = q
        return out

    def state(self, q: NDArray) -> tuple[Rotation, NDArray, NDArray, Camera]:
        full = self.full(q)
        camera = self.camera if full[9] == 0 else self.camera.with_focal(self.camera.fx * math.exp(full[9]))
        return Rotation.from_rotvec(full[0:3]) * self.rot0, full[3:6], full[6:9], camera

    def predicted(self, q: NDArray, index=slice(None)) -> NDArray[np.float64]:
        """Predictions (B, K', 6) of parameter sets q (B, P) for the streaks ``index``."""
        full = self.full(np.atleast_2d(q))
        v_mid = rotate(self.v0[index][None, :, :], -full[:, None, 0:3])  # exp([delta x]) v0
        return predict_batch(self.camera, v_mid, full[:, 3:6], full[:, 6:9], full[:, 9], self.timing)

    def steps(self) -> NDArray[np.float64]:
        """Finite-difference steps: 1e-6 rad of attitude, of turn over the exposure, of
        acceleration over the exposure, 1e-6 in ln f."""
        t = self.timing.exposure_s
        return np.array([1e-6] * 3 + [1e-6 / t] * 3 + [1e-6 / t**2] * 3 + [1e-6])[self.free]


def fit_joint(camera: Camera, stars_icrs: NDArray, measured: NDArray, cov: NDArray, rot0: Rotation,
              omega0: ArrayLike, timing: Timing, *, fit_alpha: bool = False, fit_focal: bool = False,
              outlier_chi2: float = OUTLIER_CHI2) -> JointFit:
    """Gauss-Newton fit of (attitude, omega[, alpha][, focal length]) to K streaks (module docstring).

    ``stars_icrs`` (K, 3) are the identified stars, ``measured`` (K, 6) and ``cov`` (K, 6, 6) the
    streak measurements (ends in any order), ``rot0`` and ``omega0`` the first guess (the rate's
    sign picks the time order). ``fit_focal`` also fits the focal length (a camera whose field
    was only approximately known). Streaks whose chi-square exceeds ``outlier_chi2`` are dropped
    one at a time, worst first, while at least three remain.
    """
    free = np.array([True] * 6 + [fit_alpha] * 3 + [fit_focal])
    v0 = rot0.apply(np.asarray(stars_icrs, dtype=float)).reshape(-1, 3)
    problem = _Problem(camera, v0, whitening(cov), rot0, timing, free)
    q = np.zeros(int(free.sum()))
    q[3:6] = np.asarray(omega0, dtype=float)
    used = np.ones(len(measured), dtype=bool)
    for _ in range(len(measured)):
        q, meas, predicted = _gauss_newton(problem, measured, q, used)
        chi2 = np.sum(np.einsum("kij,kj->ki", problem.white, meas - predicted) ** 2, axis=1)
        worst = int(np.argmax(np.where(used, chi2, -np.inf)))
        if chi2[worst] <= outlier_chi2 or used.sum() <= 3:
            break
        used[worst] = False
    return _result(problem, meas, q, used, chi2)


def _linearised(problem: _Problem, measured: NDArray, q: NDArray,
                used: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(the measurements (K, 6) in the time order that q predicts, the whitened residuals
    (K', 6) of the streaks ``used``, their derivatives (K', 6, P), and q's predictions (K, 6)),
    by forward differences: q and its P steps are predicted in one batch, whose first set also
    orders the ends."""
    steps = problem.steps()
    sets = q[None, :] + np.vstack([np.zeros(len(q)), np.diag(steps)])
    predicted = problem.predicted(sets)
    meas = ordered(measured, predicted[0], problem.white)
    diff = meas[used][None] - predicted[:, used]
    r = np.einsum("kij,bkj->bki", problem.white[used], diff)
    return meas, r[0], np.moveaxis((r[1:] - r[0][None]) / steps[:, None, None], 0, -1), predicted[0]


def _gauss_newton(problem: _Problem, measured: NDArray, q: NDArray, used: NDArray):
    """Iterate to convergence on the streaks ``used``; returns q, the time-ordered measurements
    (K, 6) and q's predictions (K, 6)."""
    for _ in range(MAX_ITERATIONS):
        _, r, jac, _ = _linearised(problem, measured, q, used)
        step = np.linalg.lstsq(jac.reshape(-1, len(q)), -r.ravel(), rcond=None)[0]
        q = q + step
        if np.all(np.abs(step) < 1e-2 * problem.steps()):
            break
    predicted = problem.predicted(q)[0]
    return q, ordered(measured, predicted, problem.white), predicted


def _result(problem: _Problem, meas: NDArray, q: NDArray, used: NDArray, chi2: NDArray) -> JointFit:
    _, r, jac, predicted = _linearised(problem, meas, q, used)
    a = jac.reshape(-1, len(q))
    birge = float(np.sqrt(np.sum(r**2) / max(a.shape[0] - a.shape[1], 1)))
    cov = np.zeros((10, 10))
    cov[np.ix_(problem.free, problem.free)] = np.linalg.pinv(a.T @ a) * max(birge, 1.0) ** 2
    rot, omega, alpha, camera = problem.state(q)
    return JointFit(rot, omega, alpha, cov, used, chi2, birge, meas, predicted, camera)


def information_covariance(camera: Camera, stars_icrs: NDArray, cov: NDArray, rot_mid: Rotation, omega: ArrayLike,
                           alpha: ArrayLike, timing: Timing, *, fit_alpha: bool = False,
                           fit_focal: bool = False) -> NDArray[np.float64]:
    """The Cramér-Rao covariance (10, 10) of (attitude error rotvec, omega, alpha, ln focal
    length) that K streaks measured with covariance ``cov`` (K, 6, 6; px^2) allow at the state
    (``rot_mid``, ``omega`` rad/s, ``alpha`` rad/s^2; camera frame) of stars ``stars_icrs``
    (K, 3): the inverse of the joint fit's information ``J^T C^-1 J`` with J evaluated at that
    state (the true one, to bound what any unbiased fit of these streaks can do), without the
    Birge-ratio scaling of :func:`fit_joint`. Zero rows and columns for what is not fitted."""
    free = np.array([True] * 6 + [fit_alpha] * 3 + [fit_focal])
    v0 = rot_mid.apply(np.asarray(stars_icrs, dtype=float)).reshape(-1, 3)
    problem = _Problem(camera, v0, whitening(np.asarray(cov, dtype=float)), rot_mid, timing, free)
    full = np.zeros(10)
    full[3:6], full[6:9] = np.asarray(omega, dtype=float), np.asarray(alpha, dtype=float)
    q = full[free]
    _, _, jac, _ = _linearised(problem, problem.predicted(q)[0], q, np.ones(len(v0), dtype=bool))
    a = jac.reshape(-1, len(q))
    out = np.zeros((10, 10))
    out[np.ix_(free, free)] = np.linalg.pinv(a.T @ a)
    return out

