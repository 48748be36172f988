"""Small batched 3-vector and quaternion helpers, written out for speed on tiny trailing axes
(the cross product lives in :mod:`startrack.frames`).

``numpy.cross`` and ``einsum`` spend most of their time in set-up for 3-component vectors; the
solvers call these on every problem of a batch, several times per solve.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..frames import cross


def matvec(m: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Products m v of matrices (..., 3, 3) and vectors (..., 3)."""
    return (m @ v[..., None])[..., 0]


def quat_product(p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Hamilton products of scalar-last quaternions (..., 4): ``Rotation(p) * Rotation(q)``."""
    pv, pw, qv, qw = p[..., :3], p[..., 3:], q[..., :3], q[..., 3:]
    vector = pw * qv + qw * pv + cross(pv, qv)
    scalar = pw * qw - np.sum(pv * qv, axis=-1, keepdims=True)
    return np.concatenate([vector, scalar], axis=-1)
