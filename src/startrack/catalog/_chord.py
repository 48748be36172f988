"""Angles and chords on the unit sphere: the one home of ``2 sin(theta / 2)`` and its inverse.

Two unit vectors an angle ``theta`` apart are ``2 sin(theta / 2)`` apart in 3-D, so a cone of
angular radius ``theta`` is a ball of that radius and a k-d tree answers it exactly
(:func:`startrack.catalog._cone.query_cone`). The chord is monotonic in the angle on [0, pi].
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError, is_real_number


def chord_from_angle(theta_rad: float, name: str = "theta_rad", allow_zero: bool = False) -> float:
    """Chord length ``2 sin(theta / 2)`` (unit sphere) of an angle in (0, pi] radians.

    Parameters
    ----------
    theta_rad : float
        The angle, radians: in (0, pi], or [0, pi] with ``allow_zero``.
    name : str
        The caller's parameter, named in the error.
    allow_zero : bool
        Whether 0 (a chord of 0) is valid.

    Raises
    ------
    InvalidInputError
        Naming ``name`` and the valid interval, for any other angle (NaN included).
    """
    theta = float(theta_rad) if is_real_number(theta_rad) else math.nan  # a word, None, a list: refused below
    low_ok = theta >= 0.0 if allow_zero else theta > 0.0
    if not (low_ok and theta <= math.pi):
        interval = "[0, pi]" if allow_zero else "(0, pi]"
        raise InvalidInputError(f"{name} must be in {interval} radians, got {theta_rad!r}")
    return 2.0 * math.sin(theta / 2.0)


def angle_from_chord(chord: ArrayLike) -> NDArray[np.float64]:
    """Angles ``2 arcsin(c / 2)`` (radians, shape of ``chord``) of chords on the unit sphere.

    A chord above 2 (rounding of a difference of unit vectors) gives pi; the arcsine form is exact
    at small angles, where ``arccos`` of a dot product loses half the digits.
    """
    return 2.0 * np.arcsin(np.minimum(0.5 * np.asarray(chord, dtype=float), 1.0))
