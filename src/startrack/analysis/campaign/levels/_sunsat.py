"""Jacobs 1995's matching experiment (Jacobs 1995 §3.5, Tables 3-5 to 3-7
§2.2): the Sunsat attitude region, its star lists and its guide catalogues, for the level
:mod:`._groupmatch`.

**Attitudes.** The seed drew 1000 attitudes within roll +-10 deg, pitch +-5 deg, yaw
130-140 deg, any orbit position, inclination 97 deg and node 0-120 deg. Approximated here: the
boresight is the orbit's anti-normal (declination +7 deg for i = 97 deg, right ascension set by
the node) tilted by the roll (+-10 deg) and the yaw offset (+-5 deg) along the orbit's radial
and along-track directions at a uniformly random orbit position; the camera roll follows the
orbit position plus the pitch.

**Star lists.** Every V <= 6 Hipparcos star in the 752 x 582 Sunsat field, with Gaussian
position noise sigma_p per axis (the seed does not say; per axis is the harder reading) and
magnitude noise sigma_Mv, brightest (noisy magnitude) first, at most 20 (the seed's extraction
limit); a star within 3 px of a brighter one is merged into its spot (left out). No false stars.

**Guide catalogues.** Every V <= 6 star (a pair directory of 14 deg), and the seed's
``MakeCat`` analogue: the stars within the field's half-diagonal + 0.5 deg of 20,000 boresights
sampled from the attitude region (:func:`~startrack.identify._match_groups.region_mask`), about
the seed's 540 stars.

The module name starts with an underscore, so it is not taken for a level.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ....camera import get_preset
from ....catalog import load_catalog
from ....frames import angle_between, rotation_from_radec_roll, vector_to_radec
from ....identify import PairDatabase, PairSettings, load_pair_database, region_mask, sub_catalogue
from ....units import DEG

CAMERA = get_preset("sunsat")
MAX_EXTRACTED = 20
MIN_SEPARATION_PX = 3.0
"""A star closer than this to a brighter one is part of its spot (Jacobs 1995's stars are >= 3 px wide)."""
INCLINATION = 97.0 * DEG
REGION_SAMPLES = 20_000
REGION_SEED = 20020
"""Seed of the boresights that mark the sub-catalogue's region (fixed: one catalogue for all trials)."""

SEED_ROWS = {  # Jacobs 1995 §3.5 Tables 3-5/3-6/3-7 (Jacobs 1995 §3.5, Tables 3-5/3-6/3-7)
    1: {"sigma_p_urad": 50.0, "sigma_mv": 0.3, "d_uncert_urad": 50.0, "mv_uncert": 0.3},
    2: {"sigma_p_urad": 50.0, "sigma_mv": 0.3, "d_uncert_urad": 75.0, "mv_uncert": 0.45},
    3: {"sigma_p_urad": 50.0, "sigma_mv": 0.3, "d_uncert_urad": 100.0, "mv_uncert": 0.6},
    4: {"sigma_p_urad": 50.0, "sigma_mv": 0.3, "d_uncert_urad": 150.0, "mv_uncert": 0.6},
    5: {"sigma_p_urad": 100.0, "sigma_mv": 0.3, "d_uncert_urad": 200.0, "mv_uncert": 0.45},
}
"""The noise and the tolerances of each row of the seed's tables."""


def region_pointings(n: int, rng: np.random.Generator) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Boresights (n, 3) and camera rolls (n,) (rad) of ``n`` attitudes in the seed's region
    (module docstring)."""
    node = rng.uniform(0.0, 120.0 * DEG, n)
    position = rng.uniform(0.0, 2 * math.pi, n)
    roll, yaw, pitch = (rng.uniform(-a, a, n) * DEG for a in (10.0, 5.0, 5.0))
    normal = np.column_stack([np.sin(INCLINATION) * np.sin(node), -np.sin(INCLINATION) * np.cos(node),
                              np.full(n, np.cos(INCLINATION))])
    ascending = np.column_stack([np.cos(node), np.sin(node), np.zeros(n)])
    along = np.cross(normal, ascending)
    radial = np.cos(position)[:, None] * ascending + np.sin(position)[:, None] * along
    track = np.cross(normal, radial)
    bore = -normal + roll[:, None] * radial + yaw[:, None] * track  # small-angle tilt of the anti-normal
    return bore / np.linalg.norm(bore, axis=1, keepdims=True), position + pitch


def region_attitudes(n: int, rng: np.random.Generator) -> list[Rotation]:
    """``n`` attitudes ``rot_cam_from_icrs`` in the seed's region (module docstring)."""
    bore, roll = region_pointings(n, rng)
    ra, dec = vector_to_radec(bore)
    rots = rotation_from_radec_roll(ra, dec, roll)
    return [rots[i] for i in range(n)]


@dataclass(frozen=True)
class Guides:
    """The all-sky V <= 6 pair directory, the region's sub-catalogue, and the directory stars'
    V magnitudes and HIP numbers (in the all-sky directory's order)."""

    full: PairDatabase
    sub: PairDatabase
    v_mag: NDArray[np.float64]
    hip: NDArray[np.int64]


@functools.lru_cache(maxsize=1)
def guides() -> Guides:
    """The guide catalogues (built once per process; the pair directory is cached on disk)."""
    full = load_pair_database(PairSettings(fov_deg=14.0, stars_per_field=64, max_mag=6.0))
    bores, _ = region_pointings(REGION_SAMPLES, np.random.default_rng(REGION_SEED))
    sub = sub_catalogue(full, region_mask(full, bores, math.radians(CAMERA.fov_diagonal_deg) / 2 + 0.5 * DEG))
    catalog = load_catalog()
    return Guides(full, sub, catalog.v_mag[full.catalog_rows], catalog.hip[full.catalog_rows].astype(np.int64))


@dataclass(frozen=True)
class StarList:
    """One simulated list: positions (px), noisy magnitudes and true HIP numbers, brightest first."""

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    mags: NDArray[np.float64]
    hip: NDArray[np.int64]

    def __len__(self) -> int:
        return int(self.x.size)


def star_list(truth: Rotation, g: Guides, sigma_p_rad: float, sigma_mv: float, rng: np.random.Generator) -> StarList:
    """The V <= 6 stars in the field at ``truth`` with the row's noise (module docstring)."""
    cam_vec = truth.apply(g.full.vectors)
    idx = np.flatnonzero(cam_vec[:, 2] > math.cos(math.radians(CAMERA.fov_diagonal_deg) / 2 + 0.01))
    x, y = CAMERA.vector_to_pixel(cam_vec[idx])
    x, y = x + rng.normal(0, sigma_p_rad * CAMERA.fx, x.size), y + rng.normal(0, sigma_p_rad * CAMERA.fy, y.size)
    inside = CAMERA.in_image(x, y)
    idx, x, y = idx[inside], x[inside], y[inside]
    mags = g.v_mag[idx] + rng.normal(0, sigma_mv, idx.size)
    order = np.argsort(mags, kind="stable")
    gap = np.hypot(x[order, None] - x[None, order], y[order, None] - y[None, order])
    resolved = ~np.any(np.tril(gap < MIN_SEPARATION_PX, -1), axis=1)  # no brighter star that close
    order = order[resolved][:MAX_EXTRACTED]
    return StarList(x[order], y[order], mags[order], g.hip[idx[order]])


def misidentified(got_hip: NDArray, true_hip: NDArray) -> bool:
    """Whether a star was given a HIP number whose star lies more than a pixel angle from the
    true one (the fainter component of an unresolved double, 10 arcsec away, is not a
    misidentification)."""
    bad = got_hip != true_hip
    if not np.any(bad):
        return False
    catalog = load_catalog()
    got, true = (catalog.take(np.searchsorted(catalog.hip, h[bad])).vectors(2000.0) for h in (got_hip, true_hip))
    return bool(np.any(angle_between(got, true) > 1.0 / CAMERA.fx))
