"""The star-pair directory with a k-vector (Huffman 2006 §5.5.4).

For a camera of known field of view: a uniformly thinned catalog (at most ``stars_per_field``
brightest stars around every pointing, Huffman 2006's reduced onboard catalog), every pair of those
stars closer than the field's diagonal, sorted by their angle, and a k-vector over the angles.
A range query on the angle returns the candidate pairs of an image star pair in O(1). Built on
demand into the user cache (DESIGN.md, Data).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .. import cache
from ..catalog import chord_from_angle, load_catalog, thin_uniform
from ..errors import InvalidInputError
from ._kvector import KVector

PAIRS_KIND = "pairs"
PAIRS_VERSION = 1


@dataclass(frozen=True)
class PairSettings:
    """What a pair directory is built from (its hash names the cache file).

    Attributes
    ----------
    fov_deg : float
        Diagonal field of view the directory serves: pairs up to this angle are kept.
    stars_per_field : int
        Brightest stars kept around every pointing (uniform thinning).
    max_mag : float
        Faintest star considered (V).
    epoch_jyear : float
    """

    fov_deg: float
    stars_per_field: int = 16
    max_mag: float = 9.5
    epoch_jyear: float = 2000.0

    def __post_init__(self) -> None:
        if not 0.5 <= self.fov_deg <= 120.0:
            raise InvalidInputError(f"pair directory FOV must be 0.5 to 120 deg, got {self.fov_deg:g}")
        if self.stars_per_field < 4:
            raise InvalidInputError(f"stars_per_field must be at least 4, got {self.stars_per_field}")


@dataclass(frozen=True)
class PairDatabase:
    """A loaded pair directory.

    Attributes
    ----------
    catalog_rows : ndarray of int, shape (S,)
        Rows of :func:`startrack.catalog.load_catalog` of the directory's stars.
    vectors : ndarray, shape (S, 3)
        Their ICRS unit vectors at the settings' epoch.
    pairs : ndarray of int32, shape (P, 2)
        Star indices of every pair, sorted by angle.
    angles : ndarray, shape (P,)
        Pair angles (radians), ascending; indexed by ``kvector``.
    """

    settings: PairSettings
    catalog_rows: NDArray[np.int64]
    vectors: NDArray[np.float64]
    pairs: NDArray[np.int32]
    angles: NDArray[np.float64]
    kvector: KVector = field(repr=False)
    tree: cKDTree = field(repr=False)

    def pairs_between(self, low_rad: float, high_rad: float) -> NDArray[np.int32]:
        """Pairs (K, 2) whose angle lies in [low, high] radians."""
        start, stop = self.kvector.query(low_rad, high_rad)
        return self.pairs[start:stop]


def _build(settings: PairSettings) -> dict[str, NDArray]:
    catalog = load_catalog().brighter_than(settings.max_mag)
    fov = math.radians(settings.fov_deg)
    thinned = thin_uniform(catalog, settings.stars_per_field, fov / 2.0)
    rows = np.searchsorted(load_catalog().hip, thinned.hip)  # catalog rows of the kept stars
    vectors = thinned.vectors(settings.epoch_jyear)
    pairs = np.array(sorted(cKDTree(vectors).query_pairs(chord_from_angle(fov, "fov_rad"))), dtype=np.int32)
    angles = np.arctan2(np.linalg.norm(np.cross(vectors[pairs[:, 0]], vectors[pairs[:, 1]]), axis=1),
                        np.sum(vectors[pairs[:, 0]] * vectors[pairs[:, 1]], axis=1))
    order = np.argsort(angles, kind="stable")
    return {"catalog_rows": rows.astype(np.int64), "vectors": vectors, "pairs": pairs[order], "angles": angles[order]}


_LOADED: dict[PairSettings, PairDatabase] = {}


def load_pair_database(settings: PairSettings) -> PairDatabase:
    """The pair directory for these settings, built into the cache on first use."""
    if settings not in _LOADED:
        arrays = cache.load_or_build(PAIRS_KIND, PAIRS_VERSION, asdict(settings), lambda: _build(settings))
        _LOADED[settings] = PairDatabase(settings, arrays["catalog_rows"], arrays["vectors"], arrays["pairs"],
                                         arrays["angles"], KVector.build(arrays["angles"]), cKDTree(arrays["vectors"]))
    return _LOADED[settings]
