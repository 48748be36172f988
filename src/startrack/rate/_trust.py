"""Whether a streak rate can be trusted: agreement, misfit and uncertainty of the streaks.

Not in Sease 2013, whose rate is always reported. On catalog frames a rate from a handful of faint
streaks can be confidently wrong (a few percent, mostly the roll about the boresight, which a
narrow field fixes poorly), so :mod:`._streak_rate` reports one only when enough streaks agree
(:func:`consistency`) and its covariance (:func:`rate_covariance`) is small enough.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..results import Status

MIN_AGREEING = 3
"""Fewest streaks agreeing on one rotation for a rate to be reported."""
PRECISE_END_PX = 1.0
"""Streaks whose ends are this precise (1 sigma, px) are expected to agree with the rate."""
MAX_RELATIVE_UNCERTAINTY = 0.05
"""Largest 3-sigma uncertainty of the rate vector, as a fraction of the rate, for status OK."""
def consensus_tolerance_px(end_sigma_px: ArrayLike) -> NDArray[np.float64]:
    """Largest misfit (px) of a streak agreeing with the common rotation: 1.5 px + 3 sigma of
    the difference of its two ends."""
    return 1.5 + 3.0 * np.sqrt(2.0) * np.asarray(end_sigma_px, dtype=float)


def rate_covariance(vectors: ArrayLike, end_sigma_px: ArrayLike, fx_px: float, exposure_s: float) -> NDArray:
    """Covariance (3, 3) of the rate, (rad/s)^2, from the streaks' mid vectors (N, 3) and end
    precisions (N,) px: the Wahba (QUEST) covariance ``(sum (I - v v^T) / s_i^2)^-1`` of the
    rotation between the two end sets (each streak's two ends both noisy: ``s_i^2 = 2
    (sigma_i / fx)^2``), over the exposure squared. Rotation about the boresight is the least
    determined in a narrow field."""
    v = np.asarray(vectors, dtype=float)
    v = v / np.linalg.norm(v, axis=1, keepdims=True)
    weight = 1.0 / (2.0 * (np.asarray(end_sigma_px, dtype=float) / fx_px) ** 2)
    info = np.einsum("i,ijk->jk", weight, np.eye(3)[None] - v[:, :, None] * v[:, None, :])
    return np.linalg.inv(info) / exposure_s**2


def consistency(used: ArrayLike, residuals_px: ArrayLike, end_sigma_px: ArrayLike, *,
                min_streaks: int = MIN_AGREEING, precise_px: float = PRECISE_END_PX) -> tuple[Status, str]:
    """Whether the streaks ``used`` (N,) make a trustworthy rate (status OK) or why not.

    Not OK when fewer than ``min_streaks`` streaks agree on the rotation (TOO_FEW_STARS), when
    fewer than half of the precise streaks (ends better than ``precise_px``) agree (DEGENERATE:
    the brightest, most reliable streaks disagree), or when the agreeing streaks misfit the
    rotation (rms ``residuals_px``, (N,)) by more than their end precision ``end_sigma_px``
    (N,) explains (DEGENERATE).
    """
    used = np.asarray(used, dtype=bool)
    res, sigma = np.asarray(residuals_px, dtype=float), np.asarray(end_sigma_px, dtype=float)
    if used.sum() < min_streaks:
        return Status.TOO_FEW_STARS, f"only {used.sum()} of {len(used)} streaks agree on one rotation " \
                                     f"({min_streaks} needed)"
    precise = sigma <= precise_px if len(sigma) == len(used) else np.zeros(len(used), dtype=bool)
    if precise.sum() >= min_streaks and (used & precise).sum() < 0.5 * precise.sum():
        return Status.DEGENERATE, f"only {(used & precise).sum()} of the {precise.sum()} most precise streaks " \
                                  "agree on one rotation"
    rms = float(np.sqrt(np.mean(res[used] ** 2)))
    allowed = float(np.median(consensus_tolerance_px(sigma[used]))) if len(sigma) == len(used) else 2.0
    if rms > allowed:
        return Status.DEGENERATE, f"the agreeing streaks misfit the rotation by {rms:.2f} px rms " \
                                  f"(> {allowed:.2f} px)"
    return Status.OK, ""
