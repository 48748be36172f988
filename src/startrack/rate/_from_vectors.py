"""Angular rate from the same stars seen in two frames, without a catalog.

Huffman 2006 §5.5.1 / §7.2 (§1.30-1.31: the relative attitude between frames and the
rate it implies) and Samaan 2002 step 6. The camera vectors of N stars at t_a (``vectors_a``) and at
t_b (``vectors_b``) are a Wahba problem whose solution is the relative attitude
``Delta = rot_cam_b_from_cam_a`` (``b_i ~ Delta a_i``); the rate is ``-rotvec(Delta) / dt``.
Both sets are noisy, so the effective per-star sigma is ``sqrt(sigma_a^2 + sigma_b^2)``
(Sease 2013) and the rate covariance is the QUEST covariance of Delta over dt^2.

:func:`match_frames` associates two unidentified star lists first: mutual nearest neighbours
after turning frame a by a predicted rotation (from a previous rate, or the identity), then a
second round with the rotation fitted to the first matches.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..attitude import WahbaMethod, solve_wahba
from ..catalog import chord_from_angle
from ..errors import InvalidInputError, require
from ..results import Status
from ._estimate import RateEstimate, failed

METHOD = "vectors"


def rate_from_vectors(
    vectors_a: ArrayLike,
    vectors_b: ArrayLike,
    dt_s: float,
    *,
    sigma_rad: ArrayLike | None = None,
    method: WahbaMethod = "quest",
) -> RateEstimate:
    """Camera-frame rate from N matched star directions in two frames ``dt_s`` apart.

    Parameters
    ----------
    vectors_a, vectors_b : array_like, shape (N, 3)
        Camera-frame directions of the same stars at t and t + dt_s (row i is star i in both).
    dt_s : float
        Time between the frames, seconds (non-zero).
    sigma_rad : float or array_like (N,), optional
        Per-star angular error of the *difference*, e.g. ``sqrt(sigma_a^2 + sigma_b^2)``; gives
        the rate covariance.
    method : str
        Wahba solver (:data:`startrack.attitude.METHODS`).

    Returns
    -------
    RateEstimate
        DEGENERATE status with fewer than two non-parallel stars.
    """
    if not (np.isfinite(dt_s) and dt_s != 0):
        raise InvalidInputError(f"dt_s must be finite and non-zero seconds, got {dt_s!r}")
    a = np.asarray(vectors_a, dtype=float)
    if a.ndim != 2:
        raise InvalidInputError(f"vectors_a must have shape (N, 3), got {a.shape}")
    result = solve_wahba(vectors_b, a, method=method, sigma_rad=sigma_rad)
    if not result.ok:
        return failed(Status.DEGENERATE, str(result.reason), METHOD)
    omega = -require(result.rotation, "the rotation between the frames").as_rotvec() / dt_s
    cov = None if result.covariance_rad2 is None else result.covariance_rad2 / dt_s**2
    return RateEstimate(Status.OK, omega_rad_s=omega, covariance_rad2_s2=cov, method=METHOD)


def _mutual_nearest(a: NDArray, b: NDArray, max_angle_rad: float) -> NDArray[np.intp]:
    """Index pairs (K, 2) of mutual nearest neighbours closer than the angle (chord metric)."""
    chord = chord_from_angle(min(max_angle_rad, math.pi), "max_angle_rad")
    dist_ab, nearest_b = cKDTree(b).query(a, distance_upper_bound=chord)
    _, nearest_a = cKDTree(a).query(b)
    ia = np.flatnonzero(np.isfinite(dist_ab))
    ib = nearest_b[ia]
    keep = nearest_a[ib] == ia
    return np.stack([ia[keep], ib[keep]], axis=1)


def match_frames(
    vectors_a: ArrayLike,
    vectors_b: ArrayLike,
    max_angle_rad: float,
    *,
    predicted: Rotation | None = None,
) -> NDArray[np.intp]:
    """Pairs (K, 2) of indices ``(i_a, i_b)`` of the same stars in two unidentified lists.

    Parameters
    ----------
    vectors_a, vectors_b : array_like, shape (Na, 3), (Nb, 3)
        Camera-frame unit vectors of the stars found in each frame.
    max_angle_rad : float
        Gate for the first round: the largest motion of a star between the frames left after
        the prediction (radians). Must be well under the typical star spacing.
    predicted : Rotation, optional
        Predicted ``rot_cam_b_from_cam_a`` (e.g. ``exp(-[omega x] dt)`` from a previous rate);
        the identity by default.

    Returns
    -------
    ndarray of int, shape (K, 2)
        After a second round gated at a tenth of ``max_angle_rad`` (at least 1e-4 rad) around
        the rotation fitted to the first-round pairs.
    """
    a, b = np.asarray(vectors_a, dtype=float), np.asarray(vectors_b, dtype=float)
    if a.ndim != 2 or b.ndim != 2 or a.shape[-1] != 3 or b.shape[-1] != 3:
        raise InvalidInputError(f"vectors must have shape (N, 3), got {a.shape} and {b.shape}")
    if not max_angle_rad > 0:
        raise InvalidInputError(f"max_angle_rad must be positive, got {max_angle_rad!r}")
    if len(a) == 0 or len(b) == 0:
        return np.zeros((0, 2), dtype=np.intp)
    turn = Rotation.identity() if predicted is None else predicted
    pairs = _mutual_nearest(turn.apply(a), b, max_angle_rad)
    if len(pairs) >= 2:
        fit = solve_wahba(b[pairs[:, 1]], a[pairs[:, 0]])
        if fit.ok:
            pairs = _mutual_nearest(require(fit.rotation, "the pairs' rotation").apply(a), b,
                                    max(0.1 * max_angle_rad, 1e-4))
    return pairs
