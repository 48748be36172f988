"""What every lost-in-space matcher returns: a verified candidate, or a status and reason."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..results import Status


@dataclass(frozen=True)
class Candidate:
    """A verified identification: attitude, camera, and the matched image stars with the
    catalog rows (of :func:`startrack.catalog.load_catalog`) they were matched to (the camera is
    ``mirrored`` for a mirror image of the sky, :mod:`._parity`)."""

    rot_cam_from_icrs: Rotation
    camera: Camera
    image_index: NDArray[np.int64]
    catalog_rows: NDArray[np.int64]
    false_match_prob: float


@dataclass(frozen=True)
class MatchOutcome:
    """What a matcher found: a candidate, or a status and a reason."""

    status: Status
    reason: str
    candidate: Candidate | None
    n_trials: int
