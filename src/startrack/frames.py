"""Rotations, sky directions and the RA / Dec / roll output format.

All angles in radians. Vectors are unit vectors in arrays of shape (..., 3). The attitude type is
``scipy.spatial.transform.Rotation`` named ``rot_cam_from_icrs`` (it maps ICRS vectors into the
camera frame, see :mod:`startrack.conventions`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from .errors import InvalidInputError, is_real_number

TWO_PI = 2.0 * np.pi


def radec_to_vector(ra_rad: ArrayLike, dec_rad: ArrayLike) -> NDArray[np.float64]:
    """ICRS unit vectors, shape (..., 3), from right ascension and declination in radians."""
    ra = np.asarray(ra_rad, dtype=float)
    dec = np.asarray(dec_rad, dtype=float)
    cd = np.cos(dec)
    return np.stack([cd * np.cos(ra), cd * np.sin(ra), np.sin(dec)], axis=-1)


def _wrap_2pi(angle: NDArray) -> NDArray:
    """Angles mapped into [0, 2 pi) (``np.mod`` alone can round a tiny negative up to 2 pi)."""
    wrapped = np.mod(angle, TWO_PI)
    return np.where(wrapped >= TWO_PI, 0.0, wrapped)


def vector_to_radec(v: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Right ascension in [0, 2 pi) and declination in [-pi/2, pi/2] of vectors (..., 3).

    The vectors need not be normalised. RA of a pole is 0.
    """
    v = np.asarray(v, dtype=float)
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    ra = _wrap_2pi(np.arctan2(y, x))
    dec = np.arctan2(z, np.hypot(x, y))
    return ra, dec


def normalize(v: ArrayLike) -> NDArray[np.float64]:
    """Vectors (..., 3) scaled to unit length."""
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def checked_unit_vectors(vectors: ArrayLike, name: str, shape: str = "(N, 3)") -> NDArray[np.float64]:
    """``vectors`` scaled to unit length, after checking that they have ``shape`` ("(3,)" for one
    vector, anything else such as "(N, 3)" for rows) and are finite and non-zero; an
    InvalidInputError naming ``name`` and what is wrong otherwise (pixel positions (N, 2) given for
    directions, a NaN row)."""
    one = shape == "(3,)"
    try:
        v = np.asarray(vectors, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be vectors of shape {shape}, got {vectors!r:.80}") from None
    if v.shape != (3,) if one else (v.ndim != 2 or v.shape[1] != 3):
        raise InvalidInputError(f"{name} must be vectors of shape {shape}, got shape {v.shape}")
    norms = np.linalg.norm(v, axis=-1)
    if not (np.all(np.isfinite(norms)) and np.all(norms > 0)):
        raise InvalidInputError(f"{name} must be finite, non-zero vectors (a NaN, infinite or zero "
                                f"{'vector' if one else 'row'} was given)")
    return v / norms[..., None]


def checked_angle(value: float, name: str, upper_rad: float = np.pi) -> float:
    """``value`` as a float if it is an angle in (0, ``upper_rad``] radians; else an
    InvalidInputError naming ``name`` and the range (in degrees too)."""
    if not (is_real_number(value) and np.isfinite(value) and 0 < value <= upper_rad):
        raise InvalidInputError(f"{name} must be an angle in (0, {upper_rad:.4g}] radians (0 to "
                                f"{np.degrees(upper_rad):.4g} deg), got {value!r}")
    return float(value)


def cross(u: NDArray, v: NDArray) -> NDArray[np.float64]:
    """Cross products of vectors (..., 3), broadcasting; written out, as ``np.cross`` spends most
    of its time in set-up for 3-component vectors."""
    u0, u1, u2 = u[..., 0], u[..., 1], u[..., 2]
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    return np.stack([u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0], axis=-1)


def angle_between(u: ArrayLike, v: ArrayLike) -> NDArray[np.float64]:
    """Angle in radians between vectors (..., 3), by the stable atan2 form.

    ``atan2(|u x v|, u . v)`` keeps full precision at small and near-pi angles, where
    ``arccos(u . v)`` loses it.
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    c = cross(u, v)
    return np.arctan2(np.sqrt(np.sum(c * c, axis=-1)), np.sum(u * v, axis=-1))


def _north_east(ra: NDArray, dec: NDArray) -> tuple[NDArray, NDArray]:
    """Local north and east unit tangent vectors (..., 3) at (ra, dec)."""
    sr, cr, sd, cd = np.sin(ra), np.cos(ra), np.sin(dec), np.cos(dec)
    north = np.stack([-sd * cr, -sd * sr, cd], axis=-1)
    east = np.stack([-sr, cr, np.zeros_like(ra)], axis=-1)
    return north, east


def rotation_from_radec_roll(ra_rad: ArrayLike, dec_rad: ArrayLike, roll_rad: ArrayLike) -> Rotation:
    """Attitude ``rot_cam_from_icrs`` from boresight RA, Dec and roll (radians).

    The camera's +z axis points at (ra, dec); image "up" (camera -y) lies at position angle
    ``-roll`` east of north, so roll = 0 puts north up and, for an ordinary un-mirrored image,
    east to the left. Works at the poles, where RA fixes the meaning of "north".
    Scalars give a single Rotation, arrays of shape (N,) a stacked one.
    """
    ra, dec, roll = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (ra_rad, dec_rad, roll_rad)))
    z = radec_to_vector(ra, dec)
    north, east = _north_east(ra, dec)
    up = np.cos(roll)[..., None] * north - np.sin(roll)[..., None] * east
    y = -up
    x = np.cross(y, z)
    matrix = np.stack([x, y, z], axis=-2)  # rows: camera axes in ICRS
    return Rotation.from_matrix(matrix)


def radec_roll_from_rotation(
    rot_cam_from_icrs: Rotation,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Boresight RA in [0, 2 pi), Dec, and roll in [0, 2 pi) (radians) of an attitude.

    The inverse of :func:`rotation_from_radec_roll`.
    """
    matrix = rot_cam_from_icrs.as_matrix()
    ra, dec = vector_to_radec(matrix[..., 2, :])
    y0, y1, y2 = matrix[..., 1, 0], matrix[..., 1, 1], matrix[..., 1, 2]  # camera +y in ICRS; up is -y
    sr, cr, sd, cd = np.sin(ra), np.cos(ra), np.sin(dec), np.cos(dec)
    up_east = y0 * sr - y1 * cr  # up . (-sin ra, cos ra, 0), east as in _north_east
    up_north = y0 * sd * cr + y1 * sd * sr - y2 * cd  # up . (-sin dec cos ra, -sin dec sin ra, cos dec)
    roll = _wrap_2pi(-np.arctan2(up_east, up_north))
    return ra, dec, roll


def boresight(rot_cam_from_icrs: Rotation) -> NDArray[np.float64]:
    """ICRS unit vector (..., 3) of the camera's +z axis."""
    return rot_cam_from_icrs.inv().apply(np.array([0.0, 0.0, 1.0]))


def attitude_error(truth: Rotation, estimate: Rotation) -> NDArray[np.float64]:
    """Total rotation angle (radians) between two attitudes: ``(truth * estimate.inv()).magnitude()``."""
    return (truth * estimate.inv()).magnitude()


def random_rotations(n: int | None = None, rng: np.random.Generator | int | None = None) -> Rotation:
    """Attitudes uniformly distributed over SO(3), from a seeded generator."""
    if n is not None and n < 1:
        raise InvalidInputError(f"n must be a positive number of rotations, got {n}")
    return Rotation.random(n, random_state=np.random.default_rng(rng))
