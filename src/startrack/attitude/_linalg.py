"""Small batched 3-vector and quaternion helpers, written out for speed on tiny trailing axes.

``numpy.cross`` and ``einsum`` spend most of their time in set-up for 3-component vectors; the
solvers call these on every problem of a batch, several times per solve.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def cross(u: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cross products of vectors (..., 3) (broadcasting)."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0], axis=-1)


def matvec(m: NDArray[np.float64], v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Products m v of matrices (..., 3, 3) and vectors (..., 3)."""
    return (m @ v[..., None])[..., 0]


def quat_product(p: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """Hamilton products of scalar-last quaternions (..., 4): ``Rotation(p) * Rotation(q)``."""
    pv, pw, qv, qw = p[..., :3], p[..., 3:], q[..., :3], q[..., 3:]
    vector = pw * qv + qw * pv + cross(pv, qv)
    scalar = pw * qw - np.sum(pv * qv, axis=-1, keepdims=True)
    return np.concatenate([vector, scalar], axis=-1)
