"""Attitude from matched vector pairs: Wahba solvers, covariance, averaging and kinematics.

Every solver maps reference vectors (ICRS catalog directions) onto observed ones (camera
directions), so its rotation is ``rot_cam_from_icrs``; all are reachable through
:func:`solve_wahba` (``method=`` one of :data:`METHODS`) and return a :class:`WahbaResult`
(batched over M problems). See :mod:`._wahba` for the shared pieces and the quaternion
convention; one module per solver (:mod:`._quest`, :mod:`._qmethod`, :mod:`._svd`, :mod:`._foam`,
:mod:`._esoq2`, :mod:`._olae`, :mod:`._pad`, :mod:`._triad`); :mod:`._covariance` for the QUEST
covariance (camera frame, rad^2) and the roll / cross-boresight split; :mod:`._residuals` for the
per-star fit residuals; :mod:`._averaging` (Markley's quaternion average), :mod:`._propagation`
(kinematics, relative-attitude chaining) and :mod:`._mounting` (camera to body).
"""

from ._averaging import attitude_scatter, average_quaternions, average_rotations
from ._covariance import attitude_covariance, covariance_batch, roll_cross_boresight, roll_cross_boresight_error
from ._esoq2 import esoq2
from ._foam import foam
from ._inputs import degenerate_mask
from ._mounting import body_attitude, camera_attitude, covariance_to_body, estimate_mounting, to_body
from ._olae import olae, olae_gibbs, olae_residuals
from ._pad import PredictiveUpdate, pad, predictive_update
from ._propagation import chain_relative, propagate, propagate_steps, quaternion_derivative, relative_attitude
from ._qmethod import q_method, q_method_quaternions
from ._quest import quest
from ._residuals import angle_residuals
from ._svd import svd_method
from ._triad import triad
from ._wahba import METHODS, WahbaMethod, WahbaResult, solve_wahba

__all__ = [
    "METHODS",
    "PredictiveUpdate",
    "WahbaMethod",
    "WahbaResult",
    "angle_residuals",
    "attitude_covariance",
    "attitude_scatter",
    "average_quaternions",
    "average_rotations",
    "body_attitude",
    "camera_attitude",
    "chain_relative",
    "covariance_batch",
    "covariance_to_body",
    "degenerate_mask",
    "esoq2",
    "estimate_mounting",
    "foam",
    "olae",
    "olae_gibbs",
    "olae_residuals",
    "pad",
    "predictive_update",
    "propagate",
    "propagate_steps",
    "q_method",
    "q_method_quaternions",
    "quaternion_derivative",
    "quest",
    "relative_attitude",
    "roll_cross_boresight",
    "roll_cross_boresight_error",
    "solve_wahba",
    "svd_method",
    "to_body",
    "triad",
]
