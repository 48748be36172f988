"""Angular rate from the same stars seen in two frames, without a catalog.

Huffman 2006 §5.5.1 / §7.2 (§1.30-1.31: the relative attitude between frames and the
rate it implies) and Samaan 2002 step 6. The camera vectors of N stars at t_a (``vectors_a``) and at
t_b (``vectors_b``) are a Wahba problem whose solution is the relative attitude
``Delta = rot_cam_b_from_cam_a`` (``b_i ~ Delta a_i``); the rate is ``-rotvec(Delta) / dt``.
Both sets are noisy, so the effective per-star sigma is ``sqrt(sigma_a^2 + sigma_b^2)``
(Sease 2013) and the rate covariance is the QUEST covariance of Delta over dt^2.

:func:`.frame_match.match_frames` associates two unidentified star lists first, and
:func:`.frame_match.rate_from_frames` reports the rate only when the pairs support it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..attitude import WahbaMethod, solve_wahba
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
