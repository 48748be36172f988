"""Per-star residuals of an attitude fit."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ..frames import angle_between
from ._inputs import as_vector_pair


def angle_residuals(
    rotation: Rotation, observed: ArrayLike, reference: ArrayLike
) -> NDArray[np.float64]:
    """Angle (radians) between each observed vector and its rotated reference vector.

    Parameters
    ----------
    rotation : Rotation
        Maps reference vectors into the observed frame (``rot_cam_from_icrs``); a single
        rotation, or a stack of M for batched vectors.
    observed, reference : array_like, shape (N, 3) or (M, N, 3)
        Matching observed (camera-frame) and reference (e.g. ICRS) directions.

    Returns
    -------
    ndarray, shape (N,) or (M, N)
        ``angle_between(observed, rotation.apply(reference))`` by the stable atan2 form of
        :func:`startrack.frames.angle_between`.

    Raises
    ------
    InvalidInputError
        Bad shapes, or a rotation stack whose length is not M.
    """
    obs, ref, batched = as_vector_pair(observed, reference)
    matrices = rotation.as_matrix()
    allowed = [(3, 3), (obs.shape[0], 3, 3)] if batched else [(3, 3)]
    if matrices.shape not in allowed:
        stack = f" or a stack of M = {obs.shape[0]}" if batched else ""
        raise InvalidInputError(
            f"rotation must be a single Rotation{stack}, got a stack of shape {matrices.shape[:-2]}"
        )
    rotated = np.einsum("...ij,...nj->...ni", matrices, ref if batched else ref[0])
    return angle_between(obs if batched else obs[0], rotated)
