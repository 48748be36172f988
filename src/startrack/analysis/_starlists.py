"""Seeded random star lists for lost-in-space benchmarks and campaigns (level "stars").

A star list is what a star tracker's detector hands to its identifier: centroids (x, y) in our
pixel convention (0-based pixel centres, x = column) and fluxes, brightest first. Each list is made
from a uniformly random attitude, the Hipparcos stars (``startrack.catalog``, positions moved to
``epoch_jyear``) brighter than a magnitude limit projected through a pinhole camera, and the
errors a real detector makes:

- centroid noise, N(0, sigma_px) per axis, with sigma_px drawn per list from ``sigma_px_range``;
- missing stars: a fraction drawn per list from ``missing_fraction_range`` of the real stars is
  removed at random;
- false stars (hot pixels, satellites, noise spikes): a count drawn per list from
  ``false_stars_range`` (inclusive), at uniformly random positions, magnitudes uniform over the
  faintest ``false_star_mag_span`` magnitudes down to the limit;
- magnitude noise, N(0, mag_noise) per star, so the brightness order is not the catalog's;

then the list is sorted brightest first and cut to ``max_stars``.

The magnitude limit, unless given, is chosen from the catalog so that a field of the camera's
solid angle holds ``target_stars`` stars on average over the sky (about 25, so fields have
roughly 10 to 40 stars, more towards the Milky Way).

Each list is generated from its own generator, spawned from the one passed in, so list ``i`` of
a seed is the same whatever the number of lists asked for.

Example
-------
>>> conditions = Conditions(fov_deg=12.0)                         # doctest: +SKIP
>>> lists = generate_star_lists(conditions, 10_000, rng=1)        # doctest: +SKIP
>>> lists[0].x, lists[0].y, lists[0].rot_cam_from_icrs            # doctest: +SKIP
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..frames import random_rotations

FLUX_MAG0: float = 1.0e6
"""Flux of a magnitude-0 star, in arbitrary units (flux = FLUX_MAG0 * 10**(-0.4 m))."""


@dataclass(frozen=True)
class Conditions:
    """What the star lists of one benchmark condition look like.

    Attributes
    ----------
    fov_deg : float
        Horizontal field of view of the pinhole camera, edge to edge, in degrees.
    width, height : int
        Image size in pixels.
    sigma_px_range : (float, float)
        Range of the per-list centroid noise (1-sigma per axis, pixels), drawn uniformly.
    missing_fraction_range : (float, float)
        Range of the per-list fraction of real stars removed, drawn uniformly.
    false_stars_range : (int, int)
        Inclusive range of the per-list number of false stars, drawn uniformly.
    mag_noise : float
        1-sigma error of each star's measured magnitude (mag); reorders the list.
    false_star_mag_span : float
        False stars get magnitudes uniform in [max_mag - span, max_mag].
    target_stars : float
        Mean number of catalog stars per field the automatic magnitude limit aims for.
    max_stars : int
        The list is cut to this many entries, brightest first.
    max_mag : float or None
        Magnitude limit (Johnson V); None chooses it from ``target_stars``.
    epoch_jyear : float
        Julian year (TDB) the catalog positions are propagated to (proper motion).
    """

    fov_deg: float = 15.0
    width: int = 1024
    height: int = 1024
    sigma_px_range: tuple[float, float] = (0.1, 0.5)
    missing_fraction_range: tuple[float, float] = (0.0, 0.2)
    false_stars_range: tuple[int, int] = (0, 6)
    mag_noise: float = 0.2
    false_star_mag_span: float = 3.0
    target_stars: float = 25.0
    max_stars: int = 40
    max_mag: float | None = None
    epoch_jyear: float = 2025.0

    @property
    def camera(self) -> Camera:
        """The pinhole camera of these conditions."""
        return Camera.from_fov(self.width, self.height, float(self.fov_deg))

    @property
    def name(self) -> str:
        return f"fov{self.fov_deg:g}"


@dataclass(frozen=True)
class StarList:
    """One simulated star list, brightest first, with its truth.

    Attributes
    ----------
    x, y : ndarray, shape (N,)
        Centroids in our pixel convention.
    flux : ndarray, shape (N,)
        Measured fluxes (with magnitude noise), decreasing.
    is_real : ndarray of bool, shape (N,)
        True for catalog stars, False for false stars.
    hip : ndarray of int, shape (N,)
        Hipparcos number of each real entry, -1 for false stars.
    rot_cam_from_icrs : Rotation
        The true attitude.
    sigma_px, missing_fraction : float
        The centroid noise and the missing-star fraction drawn for this list.
    n_false : int
        Number of false stars drawn (some may fall past ``max_stars``).
    max_mag : float
        The magnitude limit used.
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    flux: NDArray[np.float64]
    is_real: NDArray[np.bool_]
    hip: NDArray[np.int64]
    rot_cam_from_icrs: Rotation
    sigma_px: float
    missing_fraction: float
    n_false: int
    max_mag: float
    true_x: NDArray[np.float64] = field(repr=False, default_factory=lambda: np.zeros(0))
    true_y: NDArray[np.float64] = field(repr=False, default_factory=lambda: np.zeros(0))

    def __len__(self) -> int:
        return int(self.x.shape[0])


@dataclass(frozen=True)
class Sky:
    """The catalog stars brighter than the limit: unit vectors (N, 3), V mag (N,), HIP (N,)."""

    vectors: NDArray[np.float64]
    v_mag: NDArray[np.float64]
    hip: NDArray[np.int64]
    max_mag: float


def field_solid_angle_sr(conditions: Conditions) -> float:
    """Solid angle of the camera's rectangular pinhole field, in steradians."""
    cam = conditions.camera
    half_w = math.radians(cam.fov_deg) / 2.0
    half_h = math.radians(cam.fov_height_deg) / 2.0
    return 4.0 * math.asin(math.sin(half_w) * math.sin(half_h))


def magnitude_limit(v_mag: NDArray[np.float64], conditions: Conditions) -> float:
    """The V magnitude at which the sky holds ``target_stars`` per field on average.

    The catalog's ``v_mag`` (all sky) is sorted and read at rank
    ``target_stars * 4 pi / field_solid_angle``.
    """
    if conditions.max_mag is not None:
        return float(conditions.max_mag)
    mags = np.sort(v_mag[np.isfinite(v_mag)])
    rank = conditions.target_stars * 4.0 * math.pi / field_solid_angle_sr(conditions)
    return float(mags[min(int(math.ceil(rank)), mags.size - 1)])


def load_sky(conditions: Conditions, catalog=None) -> Sky:
    """The catalog stars for these conditions (``startrack.catalog.load_catalog()`` by default)."""
    if catalog is None:
        from ..catalog import load_catalog

        catalog = load_catalog()
    v_mag = np.asarray(catalog.v_mag, dtype=float)
    max_mag = magnitude_limit(v_mag, conditions)
    keep = np.isfinite(v_mag) & (v_mag <= max_mag)
    vectors = np.asarray(catalog.vectors(conditions.epoch_jyear), dtype=float)[keep]
    hip = np.asarray(catalog.hip)[keep].astype(np.int64)
    return Sky(vectors=vectors, v_mag=v_mag[keep], hip=hip, max_mag=max_mag)


def _visible(sky: Sky, rot: Rotation, conditions: Conditions, rng: np.random.Generator):
    """Noisy pixel positions, true positions, magnitudes and HIP of the stars in the frame."""
    cam = conditions.camera
    cos_limit = math.cos(math.radians(cam.fov_diagonal_deg) / 2.0 + 0.01)
    v_cam = rot.apply(sky.vectors)
    near = np.flatnonzero(v_cam[:, 2] > cos_limit)
    tx, ty = cam.vector_to_pixel(v_cam[near])
    sigma_px = rng.uniform(*conditions.sigma_px_range)
    x = tx + rng.normal(0.0, sigma_px, tx.shape)
    y = ty + rng.normal(0.0, sigma_px, ty.shape)
    inside = cam.in_image(x, y)
    idx = near[inside]
    return x[inside], y[inside], tx[inside], ty[inside], sky.v_mag[idx], sky.hip[idx], sigma_px


def _drop_missing(n: int, conditions: Conditions,
                  rng: np.random.Generator) -> tuple[NDArray, float]:
    """Indices of the real stars kept, and the missing fraction drawn."""
    fraction = rng.uniform(*conditions.missing_fraction_range)
    n_drop = int(round(fraction * n))
    keep = np.sort(rng.permutation(n)[n_drop:])
    return keep, float(fraction)


def _false_stars(conditions: Conditions, max_mag: float, rng: np.random.Generator):
    """Positions (x, y) and magnitudes of the false stars of one list."""
    lo, hi = conditions.false_stars_range
    n = int(rng.integers(lo, hi + 1))
    x = rng.uniform(-0.5, conditions.width - 0.5, n)
    y = rng.uniform(-0.5, conditions.height - 0.5, n)
    mag = rng.uniform(max_mag - conditions.false_star_mag_span, max_mag, n)
    return x, y, mag


def make_star_list(sky: Sky, conditions: Conditions, rng: np.random.Generator,
                   rot: Rotation | None = None) -> StarList:
    """One star list (see the module docstring) at attitude ``rot`` (``rot_cam_from_icrs``;
    uniformly random, drawn from ``rng``, when None)."""
    rot = random_rotations(rng=rng) if rot is None else rot
    x, y, tx, ty, mag, hip, sigma_px = _visible(sky, rot, conditions, rng)
    keep, fraction = _drop_missing(x.size, conditions, rng)
    fx, fy, fmag = _false_stars(conditions, sky.max_mag, rng)
    nan = np.full(fx.size, np.nan)
    all_x = np.concatenate([x[keep], fx])
    all_y = np.concatenate([y[keep], fy])
    all_mag = np.concatenate([mag[keep], fmag]) + rng.normal(0.0, conditions.mag_noise, all_x.size)
    order = np.argsort(all_mag, kind="stable")[: conditions.max_stars]
    is_real = np.arange(all_x.size) < keep.size
    return StarList(
        x=all_x[order], y=all_y[order], flux=FLUX_MAG0 * 10.0 ** (-0.4 * all_mag[order]),
        is_real=is_real[order], hip=np.concatenate([hip[keep], np.full(fx.size, -1)])[order],
        rot_cam_from_icrs=rot, sigma_px=float(sigma_px), missing_fraction=fraction,
        n_false=int(fx.size), max_mag=sky.max_mag,
        true_x=np.concatenate([tx[keep], nan])[order],
        true_y=np.concatenate([ty[keep], nan])[order],
    )


def generate_star_lists(conditions: Conditions, n: int,
                        rng: np.random.Generator | int | None = None, *, catalog=None,
                        sky: Sky | None = None) -> list[StarList]:
    """``n`` seeded star lists for one condition.

    Parameters
    ----------
    conditions : Conditions
    n : int
        Number of lists.
    rng : numpy.random.Generator, int or None
        Seed; list i is drawn from the i-th generator spawned from it.
    catalog : StarCatalog, optional
        Anything with ``hip``, ``v_mag`` and ``vectors()``; ``startrack.catalog.load_catalog()``
        by default.
    sky : optional
        The output of :func:`load_sky`, to reuse across calls.
    """
    sky = load_sky(conditions, catalog) if sky is None else sky
    children = np.random.default_rng(rng).spawn(n)
    return [make_star_list(sky, conditions, child) for child in children]
