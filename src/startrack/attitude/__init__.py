"""Attitude from matched vector pairs: Wahba solvers, covariance, averaging and kinematics.

Every solver maps reference vectors (ICRS catalog directions) onto observed ones (camera
directions), so its rotation is ``rot_cam_from_icrs``; all are reachable through
:func:`solve_wahba` (``method=`` one of :data:`METHODS`) and return a :class:`WahbaResult`
(batched over M problems). See :mod:`.wahba` for the shared pieces and the quaternion
convention; one module per solver (:mod:`.quest`, :mod:`.qmethod`, :mod:`.svd`, :mod:`.foam`,
:mod:`.esoq2`, :mod:`.olae`, :mod:`.pad`, :mod:`.triad`); :mod:`.covariance` for the QUEST
covariance (camera frame, rad^2) and the roll / cross-boresight split; :mod:`.residuals` for the
per-star fit residuals; :mod:`.averaging` (Markley's quaternion average), :mod:`.propagation`
(kinematics, relative-attitude chaining) and :mod:`.mounting` (camera to body).
"""

from .averaging import attitude_scatter, average_quaternions, average_rotations
from .covariance import attitude_covariance, covariance_batch, roll_cross_boresight, roll_cross_boresight_error
from .esoq2 import esoq2
from .foam import foam
from .mounting import body_attitude, camera_attitude, covariance_to_body, estimate_mounting, to_body
from .olae import olae, olae_gibbs, olae_residuals
from .pad import PredictiveUpdate, pad, predictive_update
from .propagation import (
    chain_relative,
    propagate,
    propagate_steps,
    quaternion_derivative,
    relative_attitude,
)
from .qmethod import q_method, q_method_quaternions
from .quest import quest
from .residuals import angle_residuals
from .svd import svd_method
from .triad import triad
from .wahba import METHODS, WahbaMethod, WahbaResult, solve_wahba

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
