"""Epoch propagation of catalog positions by rigorous linear space motion.

Model (ESA 1997, *The Hipparcos and Tycho Catalogues*, Vol. 1, §1.5.5, "rigorous" epoch
transformation): each star moves on a straight line at constant velocity in 3-D. In units of its
distance at the reference epoch, its position is the unit vector ``u0`` and its velocity is

    w = mu_alpha* p + mu_delta q + mu_r u0          (rad / yr),

with ``p``, ``q`` the local east and north unit vectors and ``mu_r = v_r * parallax / A`` the
"radial proper motion". After ``dt`` years the position is ``r = u0 + w dt``; the new direction is
``r / |r|``, the distance scale ``f = |r|`` divides the parallax, and ``w / f`` split into its
tangential and radial parts gives the new proper motions. Propagating in two steps equals
propagating in one (the model is closed), which this module relies on.

Hipparcos has no radial velocities, so the raw catalog has ``mu_r = 0``; then the distance
cancels from the direction and the parallax does not enter. What is neglected is perspective
acceleration from the true radial velocity: for Barnard's star (v_r = -110 km/s) that is about
0.05 arcsec by J2000 and 2 arcsec by J2050; for ordinary stars it is far below 1 mas.
Light-time and relativistic terms (which ERFA's ``starpm`` includes) are below 1 mas here.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..frames import radec_to_vector, vector_to_radec
from ..units import MAS


class SpaceMotion(NamedTuple):
    """Astrometric state of N stars after propagation; angles in radians, rates in mas/yr."""

    ra_rad: NDArray[np.float64]
    dec_rad: NDArray[np.float64]
    pm_ra_mas_yr: NDArray[np.float64]
    pm_dec_mas_yr: NDArray[np.float64]
    pm_radial_mas_yr: NDArray[np.float64]
    distance_scale: NDArray[np.float64]
    """New distance over old distance (the parallax is divided by it)."""


def _east_north(ra: NDArray, dec: NDArray) -> tuple[NDArray, NDArray]:
    """Unit vectors (N, 3) towards increasing RA (east, p) and increasing Dec (north, q)."""
    sr, cr, sd, cd = np.sin(ra), np.cos(ra), np.sin(dec), np.cos(dec)
    east = np.stack([-sr, cr, np.zeros_like(ra)], axis=-1)
    north = np.stack([-sd * cr, -sd * sr, cd], axis=-1)
    return east, north


def _velocity(ra, dec, pm_ra, pm_dec, pm_radial) -> tuple[NDArray, NDArray]:
    """Unit position (N, 3) and velocity (N, 3) in units of the distance per year."""
    u = radec_to_vector(ra, dec)
    east, north = _east_north(ra, dec)
    w = (np.asarray(pm_ra)[:, None] * east + np.asarray(pm_dec)[:, None] * north
         + np.asarray(pm_radial)[:, None] * u) * MAS
    return u, w


def propagate_vectors(ra_rad: ArrayLike, dec_rad: ArrayLike, pm_ra_mas_yr: ArrayLike,
                      pm_dec_mas_yr: ArrayLike, pm_radial_mas_yr: ArrayLike,
                      dt_yr: float) -> NDArray[np.float64]:
    """ICRS unit vectors (N, 3) after ``dt_yr`` years of linear space motion (module docstring).

    Inputs are arrays of shape (N,): position (radians), proper motions ``mu_alpha*`` and
    ``mu_delta`` and radial proper motion ``mu_r`` (mas/yr).
    """
    u, w = _velocity(np.asarray(ra_rad, float), np.asarray(dec_rad, float),
                     pm_ra_mas_yr, pm_dec_mas_yr, pm_radial_mas_yr)
    r = u + w * dt_yr
    return r / np.linalg.norm(r, axis=-1, keepdims=True)


def propagate_state(ra_rad: ArrayLike, dec_rad: ArrayLike, pm_ra_mas_yr: ArrayLike,
                    pm_dec_mas_yr: ArrayLike, pm_radial_mas_yr: ArrayLike,
                    dt_yr: float) -> SpaceMotion:
    """Full astrometric state (positions and proper motions) after ``dt_yr`` years.

    Same model and inputs as :func:`propagate_vectors`; returns a :class:`SpaceMotion`.
    """
    ra = np.asarray(ra_rad, float)
    u, w = _velocity(ra, np.asarray(dec_rad, float), pm_ra_mas_yr, pm_dec_mas_yr,
                     pm_radial_mas_yr)
    r = u + w * dt_yr
    scale = np.linalg.norm(r, axis=-1)
    u1 = r / scale[:, None]
    ra1, dec1 = vector_to_radec(u1)
    east, north = _east_north(ra1, dec1)
    w1 = w / (scale[:, None] * MAS)
    return SpaceMotion(ra1, dec1, np.sum(w1 * east, axis=-1), np.sum(w1 * north, axis=-1),
                       np.sum(w1 * u1, axis=-1), scale)

