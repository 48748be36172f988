"""In-flight calibration of a rig's mountings against a reference head, and drift detection.

From K rig frames, each head h whose own solution and the reference head's own solution exist in
frame k gives one relative mounting ``R_k = rot_cam_from_icrs_h,k * rot_cam_from_icrs_ref,k^-1``
(``rot_camh_from_camref``, independent of the body attitude). As in Fowler 2013's repeatability of a
fixed mount (Ch. 7 eq. 7.18 and Ch. 9 eq. 9.1, :mod:`startrack.calibrate._repeatability`):

1. the estimate is their Markley average (``Rotation.mean``), and the head's mounting is
   ``rot_cam_from_body_h = mean * rot_cam_from_body_ref``;
2. its standard error, per axis of the head's camera frame, is the standard deviation of the
   small-angle rotation vectors ``rotvec(R_k * mean^-1)`` over sqrt(K);
3. its offset from the rig's nominal mounting is ``rotvec(estimate * nominal^-1)`` (head camera
   frame), significant when large against the standard error;
4. a **drift** is a trend of those rotation vectors with time: a least-squares line per axis,
   whose slope is detected when it exceeds ``drift_sigmas`` times its standard error
   (``s / sqrt(sum (t - mean t)^2)``, s the residual scatter).

Each frame's relative mounting carries both heads' attitude errors, mostly their rolls (a few
arcseconds to tens of arcseconds for a narrow field); averaging many frames brings the standard
error down as 1 / sqrt(K).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError, require
from ..rig import CameraRig
from ._solution import RigSolution

DRIFT_SIGMAS = 4.0
"""A drift slope beyond this many standard errors (in any axis) is reported as detected."""


@dataclass(frozen=True)
class MountingEstimate:
    """One head's mounting measured against the reference head (module docstring).

    Attributes
    ----------
    head, reference : str
    n_frames : int
        Frames in which both heads had their own solution.
    rot_cam_from_reference : Rotation
        The mean relative mounting.
    rot_cam_from_body : Rotation
        The head's mounting implied by it and the reference head's nominal mounting.
    standard_error_rad : ndarray, shape (3,)
        Per axis of the head's camera frame (x, y across the boresight, z about it), rad.
    offset_rad : ndarray, shape (3,)
        ``rotvec(estimate * nominal^-1)``, head camera frame, rad.
    scatter_rad : ndarray, shape (3,)
        Standard deviation of the single frames' relative mountings per axis, rad.
    drift_rad_s : ndarray, shape (3,)
        Slope of the single frames' rotation vectors against time (rad/s; per frame when no times).
    drift_sigma_rad_s : ndarray, shape (3,)
        Standard error of that slope.
    drift_detected : bool
    """

    head: str
    reference: str
    n_frames: int
    rot_cam_from_reference: Rotation
    rot_cam_from_body: Rotation
    standard_error_rad: NDArray[np.float64]
    offset_rad: NDArray[np.float64]
    scatter_rad: NDArray[np.float64]
    drift_rad_s: NDArray[np.float64]
    drift_sigma_rad_s: NDArray[np.float64]
    drift_detected: bool

    @property
    def offset_sigmas(self) -> NDArray[np.float64]:
        """The offset from the nominal mounting in standard errors, per axis."""
        return np.abs(self.offset_rad) / self.standard_error_rad


def relative_mountings(solutions: Sequence[RigSolution], head: str, reference: str
                       ) -> tuple[Rotation | None, NDArray[np.int64]]:
    """``rot_camh_from_camref`` of every frame where both heads have their own solution, and the
    indices of those frames."""
    rotations, frames = [], []
    for k, sol in enumerate(solutions):
        own, ref = sol.heads.get(head), sol.heads.get(reference)
        if own is not None and ref is not None and own.solved and ref.solved:
            rotations.append(require(own.rot_cam_from_icrs, "a head's attitude")
                             * require(ref.rot_cam_from_icrs, "the reference head's attitude").inv())
            frames.append(k)
    if not rotations:
        return None, np.zeros(0, dtype=np.int64)
    return Rotation.concatenate(rotations), np.asarray(frames, dtype=np.int64)


def _trend(t: NDArray, values: NDArray) -> tuple[NDArray, NDArray]:
    """Least-squares slope (3,) of values (K, 3) against t (K,) and its standard error."""
    tc = t - t.mean()
    sxx = float(tc @ tc)
    if len(t) < 3 or sxx == 0.0:
        return np.zeros(3), np.full(3, np.inf)
    slope = tc @ (values - values.mean(axis=0)) / sxx
    resid = values - values.mean(axis=0) - np.outer(tc, slope)
    s = np.sqrt(np.sum(resid * resid, axis=0) / (len(t) - 2))
    return slope, s / math.sqrt(sxx)


def calibrate_mountings(solutions: Sequence[RigSolution], rig: CameraRig, times_s: ArrayLike | None = None, *,
                        min_frames: int = 3, drift_sigmas: float = DRIFT_SIGMAS) -> dict[str, MountingEstimate]:
    """Every head's mounting against the rig's reference head from many rig frames.

    Parameters
    ----------
    solutions : sequence of RigSolution
        One per frame (:func:`startrack.solve_rig`), solved or not; each head's own solution is used.
    rig : CameraRig
        Its reference head and nominal mountings.
    times_s : array_like, shape (K,), optional
        Frame times (s) for the drift slope; default the frame index.
    min_frames : int
        Fewest frames with both heads solved for an estimate (at least 3).
    drift_sigmas : float

    Returns
    -------
    dict of str to MountingEstimate
        One entry per head other than the reference that had ``min_frames`` frames.
    """
    times = np.arange(len(solutions), dtype=float) if times_s is None else np.asarray(times_s, dtype=float)
    if times.shape != (len(solutions),) or not np.all(np.isfinite(times)):
        raise InvalidInputError(f"times_s must hold one finite time per solution ({len(solutions)}), got shape "
                                f"{times.shape}")
    if min_frames < 3:
        raise InvalidInputError(f"min_frames must be at least 3, got {min_frames}")
    ref = rig.head(rig.reference)
    out = {}
    for head in rig:
        if head.name == ref.name:
            continue
        rel, frames = relative_mountings(solutions, head.name, ref.name)
        if rel is not None and len(frames) >= min_frames:
            out[head.name] = _estimate(rel, times[frames], head, ref, drift_sigmas)
    return out


def _estimate(rel: Rotation, t: NDArray, head, ref, drift_sigmas: float) -> MountingEstimate:
    mean = rel.mean()
    spread = (rel * mean.inv()).as_rotvec()
    n = len(rel)
    scatter = np.std(spread, axis=0, ddof=1)
    mount = mean * ref.rot_cam_from_body
    slope, slope_se = _trend(t, spread)
    return MountingEstimate(
        head=head.name, reference=ref.name, n_frames=n, rot_cam_from_reference=mean, rot_cam_from_body=mount,
        standard_error_rad=scatter / math.sqrt(n), offset_rad=(mount * head.rot_cam_from_body.inv()).as_rotvec(),
        scatter_rad=scatter, drift_rad_s=slope, drift_sigma_rad_s=slope_se,
        drift_detected=bool(np.any(np.abs(slope) > drift_sigmas * slope_se)))


def recalibrated(rig: CameraRig, estimates: dict[str, MountingEstimate]) -> CameraRig:
    """The rig with each estimated head's mounting replaced by its estimate."""
    heads = [replace(h, rot_cam_from_body=estimates[h.name].rot_cam_from_body) if h.name in estimates else h
             for h in rig]
    return CameraRig(heads, reference=rig.reference)
