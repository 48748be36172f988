"""The attitude of each trial: uniform on SO(3), or a Fibonacci sky lattice with random roll.

The Fibonacci lattice (González 2010, *Math. Geosci.* 42, 49) spreads the boresights of a cell's
``n`` trials almost evenly over the sphere: boresight ``k`` has ``sin(Dec) = 1 - (2k + 1) / n``
and ``RA = k * (3 - sqrt(5)) * pi`` (the golden angle); the roll is drawn from the trial's own
random stream, so trial ``k`` is the same whatever the chunking.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from ...frames import random_rotations, rotation_from_radec_roll

GOLDEN_ANGLE_RAD = math.pi * (3.0 - math.sqrt(5.0))


def fibonacci_radec(k: int, n: int) -> tuple[float, float]:
    """RA and Dec (rad) of point ``k`` (0 <= k < n) of an ``n``-point Fibonacci sphere lattice."""
    sin_dec = 1.0 - (2.0 * k + 1.0) / n
    return (k * GOLDEN_ANGLE_RAD) % (2.0 * math.pi), math.asin(sin_dec)


def trial_attitude(kind: str, k: int, n: int, rng: np.random.Generator) -> Rotation:
    """``rot_cam_from_icrs`` of trial ``k`` of a cell of ``n`` trials.

    Parameters
    ----------
    kind : {"uniform", "fibonacci"}
    k, n : int
        The trial and the cell's number of trials (used by the lattice).
    rng : numpy.random.Generator
        The trial's own stream (the uniform attitude, or the lattice point's roll, come first).
    """
    if kind == "uniform":
        return random_rotations(rng=rng)
    ra, dec = fibonacci_radec(k, n)
    return rotation_from_radec_roll(ra, dec, rng.uniform(0.0, 2.0 * math.pi))
