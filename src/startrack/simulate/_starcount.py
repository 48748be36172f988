"""How many catalog stars a camera sees: the expected number in the field, and the magnitude limit
that guarantees a minimum everywhere on the sky (Huffman 2006 §5.1, Table 5.1
§1.13 and §2.2).

**Expected count**: the stars brighter than ``max_mag`` over the whole sky times the fraction of
the sphere the image covers. A pinhole image of full angles a x b (edge to edge) covers the solid
angle ``4 asin(sin(a/2) sin(b/2))``. This is the mean over random pointings; the simulator's mean
count must agree with it (a test does this).

**Guaranteed count** (the seed's method): step the boresight over the sky on a grid of
``grid_step_deg`` in RA and Dec, and at each pointing find the magnitude of the n-th brightest
star inside the field; the limiting magnitude that gives at least n stars everywhere is the
largest of these. The seed does not say whether its "FOV" is a cone or a square, nor the roll of
the square; we give both: a cone of full angle FOV, and a square of side FOV with north up
(gnomonic projection).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..camera import Camera
from ..catalog import query_cone
from ..errors import InvalidInputError
from ..frames import radec_to_vector
from . import _checks

POINTINGS_PER_CHUNK = 4000


def field_solid_angle_sr(camera: Camera) -> float:
    """Solid angle (sr) of the pinhole image rectangle (distortion ignored)."""
    a = math.radians(camera.fov_deg)
    b = math.radians(camera.fov_height_deg)
    return 4.0 * math.asin(math.sin(a / 2.0) * math.sin(b / 2.0))


def catalog_star_count(max_mag: float) -> int:
    """Hipparcos-2 stars with estimated V <= ``max_mag`` over the whole sky."""
    from ..catalog import load_catalog

    return len(load_catalog().brighter_than(float(max_mag)))


def expected_star_count(camera: Camera, max_mag: float, n_sky: int | None = None) -> float:
    """Mean number of stars (V <= ``max_mag``) in the image over random pointings.

    ``n_sky`` is the all-sky count (default: Hipparcos-2, :func:`catalog_star_count`).
    """
    total = catalog_star_count(max_mag) if n_sky is None else n_sky
    return total * field_solid_angle_sr(camera) / (4.0 * math.pi)


def sky_grid(step_deg: float) -> NDArray[np.float64]:
    """Boresights (M, 3) on a grid of ``step_deg`` in RA and Dec (poles included once each)."""
    step = _checks.positive("grid_step_deg", step_deg)
    dec = np.arange(-90.0 + step, 90.0 - step / 2, step)
    ra = np.arange(0.0, 360.0 - step / 2, step)
    ra_g, dec_g = np.meshgrid(np.radians(ra), np.radians(dec))
    grid = radec_to_vector(ra_g.ravel(), dec_g.ravel())
    return np.concatenate([grid, [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]])


def limiting_mag_for_min_stars(vectors: NDArray, mags: NDArray, fov_deg: float, n_min: int,
                               shape: str = "circle", grid_step_deg: float = 1.0) -> float:
    """The faintest n_min-th-star magnitude over a sky grid (see the module docstring).

    Parameters
    ----------
    vectors : ndarray, shape (N, 3)
        ICRS unit vectors of the catalog stars (bright enough: at least n_min in every field).
    mags : ndarray, shape (N,)
    fov_deg : float
        Full cone angle ("circle") or side of the square ("square").
    n_min : int
    shape : {"circle", "square"}
    grid_step_deg : float

    Returns
    -------
    float
        The limiting magnitude; inf if some pointing has fewer than ``n_min`` stars of any
        magnitude in ``vectors``.
    """
    if shape not in ("circle", "square"):
        raise InvalidInputError(f"shape must be 'circle' or 'square', got {shape!r}")
    half = math.radians(_checks.positive("fov_deg", fov_deg)) / 2.0
    reach = half if shape == "circle" else math.atan(math.sqrt(2.0) * math.tan(half))
    order = np.argsort(mags, kind="stable")
    vectors, mags = np.asarray(vectors, dtype=float)[order], np.asarray(mags, dtype=float)[order]
    tree = cKDTree(vectors)
    grid = sky_grid(grid_step_deg)
    worst = -np.inf
    for lo in range(0, len(grid), POINTINGS_PER_CHUNK):
        centres = grid[lo:lo + POINTINGS_PER_CHUNK]
        found = query_cone(tree, centres, reach)
        worst = max(worst, float(np.max(_nth_brightest(centres, found, vectors, mags, n_min, shape, half))))
    return worst


def _nth_brightest(centres, found, vectors, mags, n_min, shape, half) -> NDArray[np.float64]:
    """Magnitude of the n-th brightest star inside each field (inf when there are fewer)."""
    out = np.full(len(centres), np.inf)
    for k, idx in enumerate(found):
        idx = np.sort(np.asarray(idx, dtype=np.intp))  # catalog sorted by magnitude
        if shape == "square":
            idx = idx[_in_square(centres[k], vectors[idx], half)]
        if idx.size >= n_min:
            out[k] = mags[idx[n_min - 1]]
    return out


def _in_square(centre: NDArray, v: NDArray, half: float) -> NDArray[np.bool_]:
    """Stars inside a square of half-angle ``half`` about ``centre``, north up (gnomonic)."""
    east = np.cross([0.0, 0.0, 1.0], centre)
    norm = np.linalg.norm(east)
    east = np.array([0.0, 1.0, 0.0]) if norm < 1e-12 else east / norm
    north = np.cross(centre, east)
    z = v @ centre
    limit = math.tan(half)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (z > 0) & (np.abs(v @ east) <= limit * z) & (np.abs(v @ north) <= limit * z)
