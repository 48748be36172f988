"""Camera calibration from star images: intrinsics, distortion and every frame's attitude, jointly.

Identified stars are perfect calibration targets: their directions are known to milliarcseconds.
For one or many solved frames this fits, by robust non-linear least squares (Levenberg-Marquardt
with iteratively re-weighted normal equations: the soft-L1 loss of ``scipy.optimize.least_squares``,
solved on the small normal matrix, which is much faster here than scipy's SVD of the whole
Jacobian), the lens model's parameters (focal length, pixel
aspect, principal point, Brown-Conrady k1, k2, k3, p1, p2; or Jacobs 1995's tilted-CCD model) together
with a small rotation of each frame's attitude, minimising the pixel residuals of all stars.

Then, as in Fowler 2013's checkerboard practice (Fowler 2013 Ch.4 §II.C and §IV step 6) and Jacobs 1995's
star-based calibration (Jacobs 1995 Ch. 6, App F):

1. **outliers** (a wrong match, a blended or hot pixel) are stars whose residual exceeds
   ``reject_sigma`` robust standard deviations; they are dropped and the fit repeated until the set
   of stars stops changing;
2. the final fit (plain least squares on the inliers) gives **uncertainties** from its Jacobian:
   ``cov = s^2 (J^T J)^-1`` with ``s^2`` the residual variance;
3. **pruning**: a parameter whose 3-sigma uncertainty exceeds its value (its offset from the null
   value: zero distortion, the starting principal point and aspect) is fixed at that null value and
   the fit repeated, least significant first.

The Jacobian is analytic for the Brown-Conrady model, central differences for other models.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..errors import InvalidInputError, as_float_array, check_instance
from ..results import AttitudeSolution, Status
from ._lens_models import BrownConradyModel
from ._tilted_ccd import TiltedCcdModel

DEFAULT_FIT: tuple[str, ...] = ("f", "aspect", "cx", "cy", "k1", "k2", "p1", "p2")
NEVER_PRUNED = ("f",)
RAYLEIGH_MEDIAN = float(np.sqrt(2.0 * np.log(2.0)))
"""Median of the residual distance of a 2-D Gaussian with unit sigma per axis."""


@dataclass(frozen=True)
class CalibrationFrame:
    """The identified stars of one image.

    Attributes
    ----------
    x, y : ndarray, shape (K,)
        Measured positions, our pixel convention.
    vectors_icrs : ndarray, shape (K, 3)
        Catalog (preferably apparent, :mod:`._apparent`) directions of the same stars.
    rot_cam_from_icrs : Rotation
        Starting attitude.
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    vectors_icrs: NDArray[np.float64]
    rot_cam_from_icrs: Rotation

    def __post_init__(self) -> None:
        x, y = as_float_array(self.x, "x").ravel(), as_float_array(self.y, "y").ravel()
        v = as_float_array(self.vectors_icrs, "vectors_icrs")
        check_instance(self.rot_cam_from_icrs, Rotation, "rot_cam_from_icrs")
        if x.shape != y.shape or v.shape != (x.size, 3):
            raise InvalidInputError(f"x, y must be (K,) and vectors_icrs (K, 3); got {x.shape}, {y.shape}, {v.shape}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y)) and np.all(np.isfinite(v))):
            raise InvalidInputError("calibration frame positions and vectors must be finite")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "vectors_icrs", v)

    def __len__(self) -> int:
        return int(self.x.size)

    @classmethod
    def from_solution(cls, solution: AttitudeSolution, x: ArrayLike | None = None,
                      y: ArrayLike | None = None) -> CalibrationFrame:
        """The matched stars of a solve (``x, y`` of the star list for a :func:`solve_stars` result;
        the solution's detections for :func:`solve_image`)."""
        if not solution.solved:
            raise InvalidInputError(f"only a solved frame can calibrate, this one is {solution.status.value}")
        idx = solution.matches.det_index
        if x is None or y is None:
            if solution.detections is None:
                raise InvalidInputError("give x and y (the star list) for a solution without detections")
            x, y = solution.detections.x, solution.detections.y
        return cls(np.asarray(x, float)[idx], np.asarray(y, float)[idx], solution.matches.cat_vectors,
                   solution.rot_cam_from_icrs)


@dataclass(frozen=True)
class CalibrationResult:
    """A calibration, or the reason there is none.

    Attributes
    ----------
    status : Status
        OK, or TOO_FEW_STARS when there are fewer stars than twice the parameters.
    reason : str
    camera : Camera or None
        The calibrated camera (None for the tilted-CCD model: see ``params``).
    params : dict
        Every model parameter (fitted or fixed), in the model's units (see ``lens_models``).
    sigma : dict
        1-sigma uncertainty of each fitted parameter; fixed parameters are absent.
    fitted, pruned : tuple of str
        Parameters fitted, and those fixed at their null value by the 3-sigma rule.
    rotations : list of Rotation
        ``rot_cam_from_icrs`` of every frame.
    inliers : list of ndarray of bool
        Per frame, the stars kept (False: rejected as outliers).
    residuals_px : list of ndarray, shape (K, 2)
        Per frame, the residual of every star (outliers included).
    rms_px : float
        RMS residual distance of the inliers, pixels.
    """

    status: Status
    reason: str = ""
    camera: Camera | None = None
    params: dict[str, float] = field(default_factory=dict)
    sigma: dict[str, float] = field(default_factory=dict)
    fitted: tuple[str, ...] = ()
    pruned: tuple[str, ...] = ()
    rotations: list[Rotation] = field(default_factory=list)
    inliers: list[NDArray[np.bool_]] = field(default_factory=list)
    residuals_px: list[NDArray[np.float64]] = field(default_factory=list)
    rms_px: float = float("nan")

    @property
    def n_outliers(self) -> int:
        return int(sum(np.count_nonzero(~m) for m in self.inliers))


@dataclass(frozen=True)
class _Stacked:
    """All frames' stars in one set of arrays, with the frame index of each."""

    x: NDArray
    y: NDArray
    ref: NDArray
    frame: NDArray
    base: NDArray  # (F, 3, 3) starting attitude matrices

    @classmethod
    def of(cls, frames: list[CalibrationFrame]) -> _Stacked:
        return cls(np.concatenate([f.x for f in frames]), np.concatenate([f.y for f in frames]),
                   np.concatenate([f.vectors_icrs for f in frames]),
                   np.concatenate([np.full(len(f), i) for i, f in enumerate(frames)]),
                   np.stack([f.rot_cam_from_icrs.as_matrix() for f in frames]))

    def matrices(self, rotvecs: NDArray) -> NDArray:
        return Rotation.from_rotvec(rotvecs.reshape(-1, 3)).as_matrix() @ self.base

    def vectors_cam(self, rotvecs: NDArray) -> NDArray:
        mats = self.matrices(rotvecs)
        return np.einsum("nij,nj->ni", mats[self.frame], self.ref)


class _Problem:
    """The least-squares problem: free intrinsic parameters + a rotation vector per frame."""

    def __init__(self, model, stacked: _Stacked, full: NDArray, free: NDArray[np.bool_]):
        self.model, self.stacked, self.full, self.free = model, stacked, full.copy(), free
        self.n_frames = stacked.base.shape[0]

    def unpack(self, p: NDArray) -> tuple[NDArray, NDArray]:
        full = self.full.copy()
        n = int(np.count_nonzero(self.free))
        full[self.free] = p[:n]
        return full, p[n:]

    def residuals(self, p: NDArray, mask: NDArray[np.bool_] | None = None) -> NDArray:
        full, rotvecs = self.unpack(p)
        s = self.stacked
        res = self.model.residuals(full, s.vectors_cam(rotvecs), s.x, s.y)
        return (res if mask is None else res[mask]).ravel()

    def normal_equations(self, p: NDArray, mask: NDArray[np.bool_], weights: NDArray
                         ) -> tuple[NDArray, NDArray]:
        """``J^T W J`` and ``J^T W r`` of the masked residuals, (P, P) and (P,).

        Analytic and block-sparse for models with a ``jacobian`` (each star depends on the intrinsics
        and on its own frame's rotation only; the frames' stars are contiguous), central differences
        otherwise. A rotation vector d on the left of a frame's attitude moves a camera vector c by
        ``d x c = -[c x] d`` (exact at d = 0, where the fit starts each round)."""
        if not hasattr(self.model, "jacobian"):
            jac = self._numeric_jacobian(p, mask)
            res = self.residuals(p, mask)
            return jac.T @ (weights[:, None] * jac), jac.T @ (weights * res)
        full, rotvecs = self.unpack(p)
        s = self.stacked
        c = s.vectors_cam(rotvecs)[mask]
        jac_p, jac_v = self.model.jacobian(full, c)
        res = self.model.residuals(full, c, s.x[mask], s.y[mask]).reshape(-1)
        jp = jac_p[:, :, self.free].reshape(-1, int(np.count_nonzero(self.free)))
        jr = (-np.einsum("nij,njk->nik", jac_v, _skew(c))).reshape(-1, 3)
        frame = np.repeat(s.frame[mask], 2)
        starts = np.searchsorted(frame, np.arange(self.n_frames))
        n_p = jp.shape[1]
        a = np.zeros((n_p + 3 * self.n_frames,) * 2)
        g = np.zeros(n_p + 3 * self.n_frames)
        wjp, wjr = weights[:, None] * jp, weights[:, None] * jr
        a[:n_p, :n_p] = jp.T @ wjp
        g[:n_p] = wjp.T @ res
        present = starts < frame.size
        cross_pr = _segment_sum(wjp[:, :, None] * jr[:, None, :], starts, present)  # (F, n_p, 3)
        block_rr = _segment_sum(wjr[:, :, None] * jr[:, None, :], starts, present)  # (F, 3, 3)
        g_r = _segment_sum(wjr * res[:, None], starts, present)  # (F, 3)
        for f in range(self.n_frames):
            sl = slice(n_p + 3 * f, n_p + 3 * f + 3)
            a[:n_p, sl] = cross_pr[f]
            a[sl, :n_p] = cross_pr[f].T
            a[sl, sl] = block_rr[f]
            g[sl] = g_r[f]
        return a, g

    def _numeric_jacobian(self, p: NDArray, mask: NDArray[np.bool_] | None) -> NDArray:
        """Central differences, one parameter at a time (for models without an analytic one)."""
        cols = []
        for k in range(p.size):
            h = 1e-6 * max(1.0, abs(p[k]))
            dp = np.zeros_like(p)
            dp[k] = h
            cols.append((self.residuals(p + dp, mask) - self.residuals(p - dp, mask)) / (2 * h))
        return np.stack(cols, axis=1)

    def start(self) -> NDArray:
        return np.concatenate([self.full[self.free], np.zeros(3 * self.n_frames)])


def _skew(v: NDArray) -> NDArray:
    """Cross-product matrices [v x], shape (N, 3, 3)."""
    z = np.zeros(v.shape[0])
    return np.stack([np.stack([z, -v[:, 2], v[:, 1]], -1), np.stack([v[:, 2], z, -v[:, 0]], -1),
                     np.stack([-v[:, 1], v[:, 0], z], -1)], 1)


def _segment_sum(values: NDArray, starts: NDArray, present: NDArray) -> NDArray:
    """Sums of ``values`` over contiguous row segments beginning at ``starts`` (zero for frames
    with no rows)."""
    out = np.zeros((starts.size, *values.shape[1:]))
    if np.any(present):
        out[present] = np.add.reduceat(values, starts[present], axis=0)
    return out


def _robust_sigma(res: NDArray) -> float:
    return float(np.median(np.hypot(res[:, 0], res[:, 1])) / RAYLEIGH_MEDIAN)


def _weights(res: NDArray, loss: str, f_scale: float) -> NDArray:
    """IRLS weights per residual component: soft-L1 ``1 / sqrt(1 + d^2 / f^2)`` of each star's
    residual distance d (the derivative of scipy's soft_l1 rho), or 1 for plain least squares."""
    if loss == "linear":
        return np.ones(res.size)
    d2 = np.sum(res.reshape(-1, 2) ** 2, axis=1)
    return np.repeat(1.0 / np.sqrt(1.0 + d2 / f_scale**2), 2)


def _cost(res: NDArray, loss: str, f_scale: float) -> float:
    d2 = np.sum(res.reshape(-1, 2) ** 2, axis=1)
    if loss == "linear":
        return float(np.sum(d2))
    return float(np.sum(2.0 * f_scale**2 * (np.sqrt(1.0 + d2 / f_scale**2) - 1.0)))


def _solve(problem: _Problem, p0: NDArray, mask: NDArray, loss: str, f_scale: float,
           max_iter: int = 60) -> tuple[NDArray, NDArray]:
    """Levenberg-Marquardt with iteratively re-weighted normal equations (the parameters are few,
    so the P x P normal matrix is far cheaper than an SVD of the full Jacobian).

    Returns the parameters and the plain (unweighted) normal matrix ``J^T J`` there.
    """
    if loss not in ("linear", "soft_l1"):
        raise InvalidInputError(f"loss must be 'linear' or 'soft_l1', got {loss!r}")
    p, lam = p0.copy(), 1e-3
    res = problem.residuals(p, mask)
    cost = _cost(res, loss, f_scale)
    for _ in range(max_iter):
        normal, grad = problem.normal_equations(p, mask, _weights(res, loss, f_scale))
        diag = np.diag(normal).copy()
        diag[diag <= 0] = 1.0
        while True:
            step = np.linalg.solve(normal + lam * np.diag(diag), -grad)
            new_res = problem.residuals(p + step, mask)
            new_cost = _cost(new_res, loss, f_scale)
            if new_cost <= cost or lam > 1e10:
                break
            lam *= 10.0
        if new_cost > cost:
            break
        converged = cost - new_cost <= 1e-12 * max(cost, 1e-30) or np.all(np.abs(step) <= 1e-12 * (1 + np.abs(p)))
        p, res, cost, lam = p + step, new_res, new_cost, max(lam / 10.0, 1e-9)
        if converged:
            break
    return p, problem.normal_equations(p, mask, np.ones(res.size))[0]


def _fit_with_rejection(problem: _Problem, loss: str, f_scale: float, reject_sigma: float,
                        min_reject_px: float):
    """Robust fit, reject, repeat until the inliers stop changing; then a plain fit on them."""
    n = problem.stacked.x.size
    mask = np.ones(n, dtype=bool)
    p = problem.start()
    for _ in range(8):
        p, _ = _solve(problem, p, mask, loss, f_scale)
        res = problem.residuals(p).reshape(-1, 2)
        limit = max(reject_sigma * _robust_sigma(res[mask]), min_reject_px)
        new = np.hypot(res[:, 0], res[:, 1]) <= limit
        if np.array_equal(new, mask):
            break
        mask = new
    p, normal = _solve(problem, p, mask, "linear", f_scale)
    return p, normal, mask


def _covariance(normal: NDArray, res: NDArray) -> NDArray:
    dof = max(res.size - normal.shape[0], 1)
    return np.linalg.pinv(normal) * (float(res @ res) / dof)


def _checked_setup(frames: object, camera: Camera, fit: object, model: object) -> tuple[list[CalibrationFrame], Any]:
    """The frames as a list and the lens model (default Brown-Conrady about ``camera``), each of its
    type, and ``fit`` a tuple or list of names; else an InvalidInputError naming the argument."""
    check_instance(camera, Camera, "camera")
    listed = [frames] if isinstance(frames, CalibrationFrame) else frames
    if not (isinstance(listed, list | tuple) and all(isinstance(f, CalibrationFrame) for f in listed)):
        raise InvalidInputError(f"frames must be a CalibrationFrame or a list of them, got a {type(frames).__name__}")
    if not (isinstance(fit, tuple | list) and fit and all(isinstance(name, str) for name in fit)):
        raise InvalidInputError(f"fit must be a tuple of one or more parameter names, got {fit!r}")
    model = BrownConradyModel(camera) if model is None else model
    if not isinstance(model, BrownConradyModel | TiltedCcdModel):
        raise InvalidInputError(f"model must be a BrownConradyModel, a TiltedCcdModel or None, got a "
                                f"{type(model).__name__}")
    return list(listed), model


def calibrate_from_stars(frames: list[CalibrationFrame] | CalibrationFrame, camera: Camera, *,
                         fit: tuple[str, ...] = DEFAULT_FIT, model=None, loss: str = "soft_l1",
                         f_scale_px: float = 0.5, reject_sigma: float = 4.0, min_reject_px: float = 0.3,
                         prune: bool = True) -> CalibrationResult:
    """Fit the camera model and every frame's attitude to identified stars.

    Parameters
    ----------
    frames : CalibrationFrame or list of them
        Identified stars per image, with a starting attitude each.
    camera : Camera
        Starting camera (image size, focal length; its principal point and distortion are the
        starting values and the null values for pruning).
    fit : tuple of str
        Parameters to fit, from the model's names (Brown-Conrady: ``f, aspect, cx, cy, k1, k2,
        k3, p1, p2``; see :mod:`._lens_models`). The others stay at their starting values.
    model : optional
        A lens model (default :class:`BrownConradyModel` about ``camera``; or
        :class:`startrack.calibrate._tilted_ccd.TiltedCcdModel`).
    loss, f_scale_px : str, float
        "soft_l1" (robust, as scipy's) or "linear", and the soft-L1 scale in pixels.
    reject_sigma, min_reject_px : float
        Outlier limit: ``reject_sigma`` robust sigmas of the residual distance, at least
        ``min_reject_px``.
    prune : bool
        Apply the 3-sigma rule to every fitted parameter except the focal length.

    Returns
    -------
    CalibrationResult
    """
    frames, model = _checked_setup(frames, camera, fit, model)
    unknown = set(fit) - set(model.names)
    if not frames or unknown:
        raise InvalidInputError(f"fit must name parameters among {model.names} (got unknown {sorted(unknown)}) "
                                "and frames must not be empty")
    stacked = _Stacked.of(frames)
    free = np.array([name in fit for name in model.names])
    n_unknown = int(np.count_nonzero(free)) + 3 * len(frames)
    if 2 * stacked.x.size < 2 * n_unknown:
        return CalibrationResult(status=Status.TOO_FEW_STARS,
                                 reason=f"{stacked.x.size} stars cannot fix {n_unknown} unknowns "
                                        f"(need at least {n_unknown})")
    full = model.initial()
    pruned: list[str] = []
    while True:
        problem = _Problem(model, stacked, full, free)
        p, normal, mask = _fit_with_rejection(problem, loss, f_scale_px, reject_sigma, min_reject_px)
        full_fit, _ = problem.unpack(p)
        sigma = np.sqrt(np.diag(_covariance(normal, problem.residuals(p, mask))))
        weakest = _weakest(model.names, free, full_fit, sigma) if prune else None
        if weakest is None:
            break
        free[weakest] = False
        full = full_fit.copy()
        full[weakest] = 0.0
        pruned.append(model.names[weakest])
    return _result(model, problem, p, sigma, mask, frames, tuple(pruned))


def _weakest(names, free, fitted, sigma) -> int | None:
    """Index of the least significant prunable parameter with 3 sigma > |value| (every parameter but
    the focal length is an offset from its null value, :mod:`._lens_models`), or None."""
    ratios = {}
    for k, i in enumerate(np.flatnonzero(free)):
        if names[i] not in NEVER_PRUNED and 3.0 * sigma[k] > abs(fitted[i]):
            ratios[i] = 3.0 * sigma[k] / max(abs(fitted[i]), 1e-300)
    return int(max(ratios, key=lambda k: ratios[k])) if ratios else None


def _result(model, problem: _Problem, p: NDArray, sigma: NDArray, mask: NDArray, frames,
            pruned: tuple[str, ...]) -> CalibrationResult:
    full, rotvecs = problem.unpack(p)
    res = problem.model.residuals(full, problem.stacked.vectors_cam(rotvecs), problem.stacked.x, problem.stacked.y)
    mats = problem.stacked.matrices(rotvecs)
    splits = np.cumsum([len(f) for f in frames])[:-1]
    fitted = tuple(n for n, f in zip(model.names, problem.free, strict=True) if f)
    inl = mask
    return CalibrationResult(
        status=Status.OK, camera=model.camera(full) if hasattr(model, "camera") else None,
        params=dict(zip(model.names, full.tolist(), strict=True)),
        sigma=dict(zip(fitted, sigma[:len(fitted)].tolist(), strict=True)), fitted=fitted, pruned=pruned,
        rotations=[Rotation.from_matrix(m) for m in mats], inliers=np.split(inl, splits),
        residuals_px=np.split(res, splits), rms_px=float(np.sqrt(np.mean(np.sum(res[inl] ** 2, axis=1)))))
