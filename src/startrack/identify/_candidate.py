"""What every lost-in-space matcher returns: a verified candidate, or a status and reason."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..results import Status


@dataclass(frozen=True)
class Candidate:
    """A verified identification: attitude, camera, and the matched image stars with the
    catalog rows (of :func:`startrack.catalog.load_catalog`) they were matched to (the camera is
    ``mirrored`` for a mirror image of the sky, :mod:`._parity`).

    The attitude is kept as the rotation matrix (3, 3) taking ICRS vectors to camera vectors, the
    type every stage after the matcher works in; :attr:`rot_cam_from_icrs` makes the Rotation
    only when asked (a solve never asks: building a Rotation from a matrix costs more than most
    stages of a solve, ``benchmarks/lis_benchmark.py --stages``)."""

    matrix_cam_from_icrs: NDArray[np.float64]
    camera: Camera
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    false_match_prob: float

    @cached_property
    def rot_cam_from_icrs(self) -> Rotation:
        """The attitude as a Rotation (camera from ICRS)."""
        return Rotation.from_matrix(self.matrix_cam_from_icrs)


@dataclass(frozen=True)
class MatchOutcome:
    """What a matcher found: a candidate, or a status and a reason."""

    status: Status
    reason: str
    candidate: Candidate | None
    n_trials: int
