"""Star availability: how many catalog stars a camera sees over random pointings (Jacobs 1995 §5.1,
Fig. 5-1 and Table 5-1; Huffman 2006 §5.1, Table 5.1).

Boresights and rolls are uniformly random over SO(3); a star counts when it projects inside the
image (the real rectangular field, through the camera model), not merely inside a cone.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from ..camera import Camera
from ..catalog import load_catalog, query_cone
from ..errors import InvalidInputError
from ..frames import random_rotations

CHUNK = 20_000
"""Pointings processed at once (bounds the memory of one step)."""


@dataclass(frozen=True)
class Availability:
    """Star counts over random pointings and their summary.

    Attributes
    ----------
    counts : ndarray of int, shape (n_pointings,)
        Stars inside the image at each pointing.
    max_mag : float
        Catalog magnitude limit (V).
    n_catalog : int
        Catalog stars to that limit.
    """

    counts: NDArray[np.int64]
    max_mag: float
    n_catalog: int

    def probability(self, n_stars: int) -> float:
        """Fraction of pointings with exactly ``n_stars`` stars."""
        return float(np.mean(self.counts == n_stars))

    def probability_below(self, n_stars: int) -> float:
        """Fraction of pointings with fewer than ``n_stars`` stars."""
        return float(np.mean(self.counts < n_stars))

    @property
    def histogram(self) -> NDArray[np.int64]:
        """Number of pointings with 0, 1, 2, ... stars."""
        return np.bincount(self.counts)


def star_counts(camera: Camera, max_mag: float, n_pointings: int, rng: np.random.Generator | int | None = None,
                progress: Callable[[int, int], None] | None = None) -> Availability:
    """Count the catalog stars (V <= ``max_mag``) inside the image at random pointings.

    Parameters
    ----------
    camera : Camera
        Its image rectangle, focal length and distortion decide what is "in the field".
    max_mag : float
        Catalog limit (estimated Johnson V, see :mod:`startrack.catalog`).
    n_pointings : int
        Random attitudes (uniform over SO(3)); Jacobs 1995 used 10^6.
    rng : Generator, int or None
    progress : callable(done, total), optional
    """
    if not (isinstance(n_pointings, int | np.integer) and n_pointings >= 1):
        raise InvalidInputError(f"n_pointings must be a positive whole number, got {n_pointings!r}")
    catalog = load_catalog().brighter_than(max_mag)
    vectors = catalog.vectors()
    tree = cKDTree(vectors)
    rng = np.random.default_rng(rng)
    reach = min(math.radians(camera.fov_diagonal_deg) / 2.0 * 1.02, math.pi / 2)
    counts = np.zeros(n_pointings, dtype=np.int64)
    for start in range(0, n_pointings, CHUNK):
        stop = min(start + CHUNK, n_pointings)
        counts[start:stop] = _count_chunk(camera, vectors, tree, random_rotations(stop - start, rng), reach)
        if progress is not None:
            progress(stop, n_pointings)
    return Availability(counts, float(max_mag), len(catalog))


def _count_chunk(camera: Camera, vectors: NDArray, tree: cKDTree, rotations, reach_rad: float) -> NDArray[np.int64]:
    matrices = rotations.as_matrix()  # (P, 3, 3), rows = camera axes in ICRS
    found = query_cone(tree, matrices[:, 2, :], reach_rad, return_sorted=False)
    lengths = np.fromiter((len(f) for f in found), dtype=np.int64, count=len(found))
    stars = np.fromiter(itertools.chain.from_iterable(found), dtype=np.int64, count=int(lengths.sum()))
    pointing = np.repeat(np.arange(len(found)), lengths)
    cam = np.einsum("pij,pj->pi", matrices[pointing], vectors[stars])
    x, y = camera.vector_to_pixel(cam)
    inside = camera.in_image(x, y)
    return np.bincount(pointing[inside], minlength=len(found))
