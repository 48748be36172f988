"""Frame-to-frame identification without a catalog: the relative attitude between two frames
from their stars alone (Huffman 2006 §5.5.2-5.5.3 triangle match and
§1.22 rate match).

* :func:`triangle_match`: triads of the first frame's brightest stars (Mortari's order); the
  second frame's triangles whose three angles (within the tolerance) and handedness fit; the
  rotation of the three pairs, confirmed by how many other stars it carries onto a star of the
  second frame. Needs no prior.
* :func:`rate_match`: the first frame's stars turned by the known rate over the frame interval
  and matched to the nearest second-frame star within the tolerance.

Both end with the q-method over every matched pair. The rotation returned maps first-frame
camera vectors onto second-frame ones: ``rot_cam2_from_cam1``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..attitude import q_method_quaternions
from ..errors import InvalidInputError, is_real_number
from ..frames import angle_between, checked_angle, checked_unit_vectors
from ..identify import pyramid_triads
from ..results import Status
from ._inputs import checked_rate

MIN_CONFIRMED = 4
"""Matched pairs (the three of the triangle included) needed to accept a relative attitude."""

MAX_TOL_RAD = 0.1
"""Largest angle tolerance taken (radians, 5.7 deg): a few centroid sigmas over the focal length
are far less; a tolerance near the stars' spacing matches any star to any other, and a triangle
to one of another shape, so that "confirmed" would mean nothing."""


def _frames(first: ArrayLike, second: ArrayLike) -> tuple[NDArray, NDArray]:
    """The two frames' camera-frame directions (N1, 3), (N2, 3), checked and of unit length."""
    return checked_unit_vectors(first, "first"), checked_unit_vectors(second, "second")


@dataclass(frozen=True)
class RelativeMatch:
    """The relative attitude of two frames, or the reason there is none.

    Attributes
    ----------
    status : Status
    rot_cam2_from_cam1 : Rotation or None
    index1, index2 : ndarray of int, shape (K,)
        Matched stars of the first and second frame.
    residual_rms_rad : float
    """

    status: Status
    rot_cam2_from_cam1: Rotation | None = None
    index1: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    index2: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    residual_rms_rad: float = float("nan")
    reason: str = ""


def _q_method(first: NDArray, second: NDArray) -> NDArray:
    weights = np.full((1, len(first)), 1.0 / len(first))
    return Rotation.from_quat(q_method_quaternions(second[None], first[None], weights)[0]).as_matrix()


def _nearest_pairs(predicted: NDArray, second: NDArray, tol_rad: float) -> tuple[NDArray, NDArray]:
    """Each predicted vector's nearest second-frame vector within ``tol_rad``, one-to-one."""
    ang = angle_between(predicted[:, None, :], second[None, :, :])
    i, j = np.nonzero(ang <= tol_rad)
    order = np.argsort(ang[i, j], kind="stable")
    used1, used2, keep = set(), set(), []
    for k in order:
        if i[k] not in used1 and j[k] not in used2:
            used1.add(i[k])
            used2.add(j[k])
            keep.append(k)
    return i[keep].astype(np.int64), j[keep].astype(np.int64)


def _finish(first: NDArray, second: NDArray, matrix: NDArray, tol_rad: float) -> RelativeMatch:
    """Match everything under ``matrix``, refit on all pairs, and decide."""
    i1, i2 = _nearest_pairs(first @ matrix.T, second, tol_rad)
    if i1.size < MIN_CONFIRMED:
        return RelativeMatch(Status.NO_MATCH, reason=f"only {i1.size} stars matched between the frames")
    matrix = _q_method(first[i1], second[i2])
    i1, i2 = _nearest_pairs(first @ matrix.T, second, tol_rad)
    matrix = _q_method(first[i1], second[i2])
    residual = angle_between(first[i1] @ matrix.T, second[i2])
    return RelativeMatch(Status.OK, Rotation.from_matrix(matrix), i1, i2, float(np.sqrt(np.mean(residual**2))))


def triangle_match(first: ArrayLike, second: ArrayLike, tol_rad: float, max_stars: int = 12) -> RelativeMatch:
    """Relative attitude of two frames by matching a triangle of stars (no prior, no catalog).

    Parameters
    ----------
    first, second : array_like, shape (N1, 3), (N2, 3)
        Camera-frame unit vectors of the two frames' stars, brightest first.
    tol_rad : float
        Angle tolerance (radians, in (0, :data:`MAX_TOL_RAD`]): a few centroid sigmas over the
        focal length.
    max_stars : int
        Brightest first-frame stars used for triads (at least 3).

    Raises
    ------
    InvalidInputError
        Directions that are not finite non-zero vectors (N, 3), a tolerance out of range.
    """
    first, second = _frames(first, second)
    tol_rad = checked_angle(tol_rad, "tol_rad", MAX_TOL_RAD)
    if isinstance(max_stars, bool) or not isinstance(max_stars, int | np.integer) or max_stars < 3:
        raise InvalidInputError(f"max_stars must be an integer >= 3 (a triangle's stars), got {max_stars!r}")
    if len(first) < 3 or len(second) < 3:
        return RelativeMatch(Status.TOO_FEW_STARS, reason="each frame needs at least 3 stars")
    second_angles = angle_between(second[:, None, :], second[None, :, :])
    for triad in pyramid_triads(min(len(first), max_stars)):
        tri1 = first[list(triad)]
        for tri2 in _triangles_in(second_angles, angle_between(tri1[[0, 0, 1]], tri1[[1, 2, 2]]), tol_rad):
            if np.sign(np.linalg.det(second[tri2])) != np.sign(np.linalg.det(tri1)):
                continue  # a mirror image of the triangle
            found = _finish(first, second, _q_method(tri1, second[tri2]), tol_rad)
            if found.status is Status.OK:
                return found
    return RelativeMatch(Status.NO_MATCH, reason="no triangle of the first frame was found in the second")


def _triangles_in(angles2: NDArray, legs: NDArray, tol_rad: float) -> list[NDArray]:
    """Triples (a, b, c) of second-frame stars whose angles a-b, a-c, b-c fit ``legs``."""
    ab = np.argwhere(np.abs(angles2 - legs[0]) <= tol_rad)
    out: list[NDArray] = []
    for a, b in ab:
        cs = np.flatnonzero((np.abs(angles2[a] - legs[1]) <= tol_rad) & (np.abs(angles2[b] - legs[2]) <= tol_rad))
        out.extend(np.array([a, b, c]) for c in cs if c not in (a, b))
    return out


def rate_match(first: ArrayLike, second: ArrayLike, rate_rad_s: ArrayLike, dt_s: float,
               tol_rad: float) -> RelativeMatch:
    """Relative attitude of two frames from a known rate: predict, match the nearest, refit.

    ``rate_rad_s`` (3,) is the camera's angular velocity in its own frame (rad/s, finite); stars
    turn by ``-rate * dt_s`` between the frames, ``dt_s`` (s) finite and non-zero. ``first``,
    ``second`` and ``tol_rad`` as for :func:`triangle_match`; InvalidInputError for any of them
    out of range.
    """
    first, second = _frames(first, second)
    tol_rad = checked_angle(tol_rad, "tol_rad", MAX_TOL_RAD)
    rate = checked_rate(rate_rad_s, name="rate_rad_s")
    if not (is_real_number(dt_s) and math.isfinite(dt_s) and dt_s != 0):
        raise InvalidInputError(f"dt_s must be a finite, non-zero number of seconds between the frames, got {dt_s!r}")
    if len(first) < MIN_CONFIRMED or len(second) < MIN_CONFIRMED:
        return RelativeMatch(Status.TOO_FEW_STARS, reason=f"each frame needs at least {MIN_CONFIRMED} stars")
    predicted = Rotation.from_rotvec(-rate * dt_s).as_matrix()
    return _finish(first, second, predicted, tol_rad)
