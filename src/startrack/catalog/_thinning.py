"""Uniform thinning: an even sky density of bright stars (a reduced onboard catalog).

Huffman 2006 §5.5.4: step the boresight over the whole sky and keep the 8
brightest stars in the field of view at each pointing; the union is the reduced catalog. Jacobs 1995
§5.2 builds its sub-catalogues from sky regions in the same spirit. Here the
pointings are a Fibonacci lattice on the sphere with one point per ``spacing**2`` steradians
(spacing = the region radius by default), so the regions overlap and cover every direction
(the lattice's covering radius is about 0.77 of its spacing). The rule is deterministic: ties in
magnitude go to the star earlier in the catalog.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..errors import InvalidInputError, check_instance, checked_count, checked_number
from ._chord import chord_from_angle
from ._cone import query_cone
from ._star_catalog import StarCatalog

GOLDEN_ANGLE_RAD = np.pi * (3.0 - np.sqrt(5.0))


def fibonacci_sphere(n_points: int) -> NDArray[np.float64]:
    """``n_points`` evenly spread unit vectors (n_points, 3): a spherical Fibonacci lattice."""
    n = int(n_points)
    if n < 1:
        raise InvalidInputError(f"n_points must be a positive integer, got {n_points!r}")
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    rho = np.sqrt(1.0 - z * z)
    phi = GOLDEN_ANGLE_RAD * i
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=-1)


MIN_SPACING_RAD = 1e-3
"""The finest lattice of sample directions (rad, 3.4 arcmin): 12.6 million points. A finer one asked
for more memory than exists (and 1e-300 divided by zero)."""


def sky_sample_points(spacing_rad: float, name: str = "spacing_rad") -> NDArray[np.float64]:
    """Fibonacci-lattice directions (M, 3) with about ``spacing_rad`` between neighbours (in
    [:data:`MIN_SPACING_RAD`, pi]; else an InvalidInputError naming ``name``).

    ``M = ceil(4 pi / spacing**2)``: each point stands for ``spacing**2`` steradians.
    """
    spacing = checked_number(spacing_rad, f"{name} (radians)", low=MIN_SPACING_RAD, high=math.pi)
    return fibonacci_sphere(int(np.ceil(4.0 * np.pi / spacing**2)))


def _regions(vectors: NDArray, centers: NDArray, radius_rad: float) -> tuple[NDArray, NDArray]:
    """(region index, star index) of every star within ``radius_rad`` of every centre, flattened."""
    members = query_cone(cKDTree(vectors), centers, radius_rad, workers=-1)
    counts = np.fromiter((len(m) for m in members), dtype=np.int64, count=len(members))
    stars = np.fromiter((j for m in members for j in m), dtype=np.int64, count=int(counts.sum()))
    return np.repeat(np.arange(len(centers)), counts), stars


def thin_uniform(catalog: StarCatalog, max_per_region: int, region_radius_rad: float, *,
                 band: str = "v", spacing_rad: float | None = None) -> StarCatalog:
    """Keep each star that is among the ``max_per_region`` brightest within ``region_radius_rad``
    of at least one sky sample point; the result is sorted brightest first.

    Parameters
    ----------
    catalog : the stars (positions at the catalog epoch).
    max_per_region : how many of the brightest stars each region keeps (Huffman 2006: 8 per FOV).
    region_radius_rad : radius of each circular region, e.g. half the field of view (radians).
    band : "v" or "hp", the magnitude that ranks brightness.
    spacing_rad : spacing of the sample points (:func:`sky_sample_points`); defaults to
        ``region_radius_rad``.

    Returns
    -------
    StarCatalog
        The union of the regions' brightest stars. A region can hold more than
        ``max_per_region`` of them (stars kept for neighbouring regions), but each region holds
        at least ``min(max_per_region, stars there)``. No randomness is involved.
    """
    check_instance(catalog, StarCatalog, "catalog")
    k = checked_count(max_per_region, "max_per_region", 1)
    chord_from_angle(region_radius_rad, "region_radius_rad")  # refuses an angle outside (0, pi]
    centers = sky_sample_points(region_radius_rad, "region_radius_rad") if spacing_rad is None else \
        sky_sample_points(spacing_rad)
    order = np.argsort(catalog.magnitudes(band), kind="stable")  # brightness rank -> star
    region, rank = _regions(catalog.vectors()[order], centers, region_radius_rad)
    by_region = np.lexsort((rank, region))
    region, rank = region[by_region], rank[by_region]
    position = np.arange(len(rank)) - np.searchsorted(region, region)
    kept_ranks = np.unique(rank[position < k])
    return catalog.take(order[kept_ranks])
