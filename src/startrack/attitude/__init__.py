"""Attitude from matched vector pairs: Wahba solvers, covariance and residuals.

Every solver maps reference vectors (ICRS catalog directions) onto observed ones (camera
directions), so its rotation is ``rot_cam_from_icrs``; see :mod:`.wahba` for the shared pieces
and the quaternion convention, :mod:`.quest` and :mod:`.qmethod` for the solvers,
:mod:`.covariance` for the QUEST covariance (camera frame, rad^2) and :mod:`.residuals` for the
per-star fit residuals.
"""

from .covariance import attitude_covariance
from .qmethod import q_method
from .quest import quest
from .residuals import angle_residuals
from .wahba import METHODS, WahbaResult, solve_wahba

__all__ = [
    "METHODS",
    "WahbaResult",
    "angle_residuals",
    "attitude_covariance",
    "q_method",
    "quest",
    "solve_wahba",
]
