"""Attitude arithmetic on one scalar-last quaternion at a time, for the tracking loop.

A tracking step turns the last attitude by the rate, fits two small attitudes and measures the
rate between frames. scipy's :class:`~scipy.spatial.transform.Rotation` pays array-API
dispatch and input checks on every call, which on one attitude at a time is most of a tracking
step's cost (``benchmarks/tracking_benchmark.py`` times the steps). These helpers do the same
arithmetic on plain floats, without that overhead. Quaternions are ``(x, y, z, w)`` tuples, scipy's order and
meaning: ``quat_product(p, q)`` is ``Rotation(p) * Rotation(q)`` (q applied first).

* :func:`rotvec_quat` and :func:`quat_rotvec`: the exponential and log maps (the exact form of
  the constant-rate kinematics, Sease 2013 Eq. 2.12, and of the rate between two attitudes,
  Samaan 2002 step 6 eq. 3 / Sease 2013 eqs. 3.24-3.27, as in :mod:`startrack.rate._from_attitudes`).
* :func:`fit_quat`: Davenport's q-method (Huffman 2006 §6.1.3) with equal weights, as
  :mod:`startrack.attitude._qmethod` with the batch layer and its checks left out.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Quat = tuple[float, float, float, float]

def quat_product(p: Quat, q: Quat) -> Quat:
    """Hamilton product of scalar-last quaternions: the rotation ``Rotation(p) * Rotation(q)``."""
    px, py, pz, pw = p
    qx, qy, qz, qw = q
    return (pw * qx + qw * px + py * qz - pz * qy,
            pw * qy + qw * py + pz * qx - px * qz,
            pw * qz + qw * pz + px * qy - py * qx,
            pw * qw - px * qx - py * qy - pz * qz)


def quat_conjugate(q: Quat) -> Quat:
    """The inverse rotation of a unit quaternion."""
    return (-q[0], -q[1], -q[2], q[3])


def rotvec_quat(rotvec: NDArray[np.float64] | tuple[float, float, float]) -> Quat:
    """Unit quaternion of the rotation by ``|rotvec|`` radians about ``rotvec`` (exp map)."""
    x, y, z = (float(v) for v in rotvec)
    angle = math.sqrt(x * x + y * y + z * z)
    scale = math.sin(angle / 2.0) / angle if angle > 0.0 else 0.5
    return (scale * x, scale * y, scale * z, math.cos(angle / 2.0))


def quat_rotvec(q: Quat) -> NDArray[np.float64]:
    """Rotation vector (3,), radians, of a unit quaternion, angle in [0, pi] (log map)."""
    x, y, z, w = q
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    sine = math.sqrt(x * x + y * y + z * z)
    angle = 2.0 * math.atan2(sine, w)
    scale = angle / sine if sine > 0.0 else 2.0
    return np.array([scale * x, scale * y, scale * z])


def quat_matrix(q: Quat) -> NDArray[np.float64]:
    """Rotation matrix (3, 3) of a quaternion (normalised here)."""
    x, y, z, w = q
    n = 2.0 / (x * x + y * y + z * z + w * w)
    xx, yy, zz = n * x * x, n * y * y, n * z * z
    xy, xz, yz = n * x * y, n * x * z, n * y * z
    wx, wy, wz = n * w * x, n * w * y, n * w * z
    return np.array([[1.0 - yy - zz, xy - wz, xz + wy],
                     [xy + wz, 1.0 - xx - zz, yz - wx],
                     [xz - wy, yz + wx, 1.0 - xx - yy]])


def fit_quat(observed: NDArray[np.float64], reference: NDArray[np.float64]) -> Quat:
    """Equal-weight q-method: the unit quaternion of R minimising ``sum |b_i - R r_i|^2``.

    Parameters
    ----------
    observed : ndarray, shape (N, 3)
        Unit vectors b_i in the camera frame (N >= 2, not all parallel).
    reference : ndarray, shape (N, 3)
        Matching unit vectors r_i in ICRS.

    Returns
    -------
    tuple of 4 floats
        Scalar-last quaternion of ``rot_cam_from_icrs``.
    """
    b = (observed.T @ reference).ravel() / len(observed)  # profile matrix B = sum w b r^T, row-major
    b00, b01, b02, b10, b11, b12, b20, b21, b22 = b.tolist()
    sigma = b00 + b11 + b22
    z0, z1, z2 = b21 - b12, b02 - b20, b10 - b01  # sum w (r x b), the active-convention z
    k = np.array([[2.0 * b00 - sigma, b01 + b10, b02 + b20, z0],
                  [b01 + b10, 2.0 * b11 - sigma, b12 + b21, z1],
                  [b02 + b20, b12 + b21, 2.0 * b22 - sigma, z2],
                  [z0, z1, z2, sigma]])
    _, vectors = np.linalg.eigh(k)  # eigenvalues ascending: the last column is the optimum
    return tuple(vectors[:, 3].tolist())
