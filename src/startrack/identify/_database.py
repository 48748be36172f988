"""The pattern database: four-star patterns at several field-of-view scales, with a sorted key index.

Built on demand from the Hipparcos catalog into the user cache (DESIGN.md, Data) and loaded from
there afterwards.

How it is built (the uniform reduced catalog of Huffman 2006 §5.5.4 and Jacobs 1995's sub-catalogue,
applied per scale):

1. Stars to ``max_mag`` (estimated V), at ``epoch_jyear``; stars with a neighbour closer than
   ``blend_fraction`` of a level's FOV are left out of that level's patterns (their centroids
   blend in an image), unless the neighbour is more than ``blend_delta_mag`` fainter (it barely
   moves the centroid; before this rule, a V 3 star with any V 9 star within 6 arcmin was left
   out, and sparse wide fields of bright stars had no pattern at all).
2. Levels: fields of view from ``fov_max_deg`` down to ``fov_min_deg`` in steps of
   ``level_ratio``. At each level, sample directions cover the sky (a Fibonacci lattice) at a
   spacing of half the region radius ``region_fraction * FOV``; around each, the
   ``stars_per_region`` brightest stars form every four-star pattern (C(6, 4) = 15 for 6 stars).
   Duplicates are removed.
3. Each pattern is keyed by its five sorted edge ratios (:mod:`._patterns`); each level's patterns
   are sorted by a key of its three smallest ratios (:func:`pattern_key`). The keys of all levels,
   prefixed by their level, form one sorted array (:attr:`PatternDatabase.keys`, stored with the
   patterns rather than computed at each load, where it was a large part of the load time;
   ``benchmarks/startup_benchmark.py`` times the load),
   so that every range query of a batch of image patterns, over every level, is one binary
   search (:meth:`PatternDatabase.key_ranges`). In numpy that is faster than a k-vector per
   level (measured: the k-vector's exact trimming gathers a window per query); the k-vector
   indexes the star-pair directory (:mod:`._pair_database`).
4. Each level also keeps a verification set: the ``verify_per_region`` brightest stars around each
   sample direction within half the FOV, to confirm a match and measure its false-match
   probability (:mod:`._verify`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from .. import cache
from ..catalog import fibonacci_sphere, flag_doubles, load_catalog, query_cone
from ..errors import InvalidInputError, require
from ._patterns import edge_ratios, pair_angles

DB_KIND = "patterns"
DB_VERSION = 4
"""3: largest edges stored on a logarithmic scale (fields of view to 120 deg), star and level
masks widened when needed; 4: the key index (:attr:`PatternDatabase.keys`, ``cell_starts``)
stored, not recomputed at each load."""

DB_MAX_FOV_DEG = 160.0
"""Widest level a database may reach: the widest field a solve takes (``_request.MAX_FOV_DEG``,
150 deg) with the tolerance of a given FOV and the database's margin (3 % each)."""


@dataclass(frozen=True)
class DatabaseSettings:
    """What a pattern database is built from; its hash names the cache file."""

    fov_min_deg: float = 3.0
    fov_max_deg: float = 100.0
    level_ratio: float = 1.4
    stars_per_region: int = 6
    region_fraction: float = 0.35
    verify_per_region: int = 24
    max_mag: float = 9.5
    blend_fraction: float = 1.0 / 250.0
    blend_delta_mag: float = 3.0
    min_edge_fraction: float = 1.0 / 150.0
    epoch_jyear: float = 2000.0

    def __post_init__(self) -> None:
        if not (0.4 <= self.fov_min_deg <= self.fov_max_deg <= DB_MAX_FOV_DEG):
            raise InvalidInputError(
                f"database FOV range must satisfy 0.4 <= fov_min_deg <= fov_max_deg <= {DB_MAX_FOV_DEG:g} deg, "
                f"got {self.fov_min_deg} to {self.fov_max_deg}")
        if self.level_ratio <= 1.05 or self.stars_per_region < 4:
            raise InvalidInputError("level_ratio must exceed 1.05 and stars_per_region be at least 4")

    def level_fovs_rad(self) -> NDArray[np.float64]:
        """Fields of view of the levels, narrowest first (radians), from fov_min to >= fov_max."""
        count = 1 + math.ceil(math.log(self.fov_max_deg / self.fov_min_deg) / math.log(self.level_ratio) - 1e-9)
        return np.radians(self.fov_min_deg * self.level_ratio ** np.arange(count))


@dataclass(frozen=True)
class PatternDatabase:
    """A loaded pattern database (see the module docstring for how it is built).

    Attributes
    ----------
    settings : DatabaseSettings
    cat_index : ndarray of int, shape (S,)
        Row of each database star in :func:`startrack.catalog.load_catalog`.
    hip : ndarray of int, shape (S,)
    vectors : ndarray, shape (S, 3)
        ICRS unit vectors at ``settings.epoch_jyear``.
    mag : ndarray, shape (S,)
    level_fov_rad : ndarray, shape (L,)
    pattern_stars : ndarray of uint16 (uint32 beyond 65,536 stars), shape (P, 4)
        Database-star indices of each pattern (patterns sorted by level, then :func:`pattern_key`).
    pattern_ratios : ndarray of uint16, shape (P, 5)
        Sorted edge ratios times :data:`RATIO_SCALE`.
    pattern_largest : ndarray of uint16, shape (P,)
        Largest edge angle of each pattern on a logarithmic scale (:func:`largest_from_stored`).
    level_offsets : ndarray of int, shape (L + 1,)
        Patterns of level k are rows ``level_offsets[k]:level_offsets[k + 1]``.
    verify_levels : ndarray of uint16 (uint32 beyond 16 levels), shape (S,)
        Bit k set when the star belongs to level k's verification set.
    keys : ndarray of int64, shape (P,)
        ``(level << LEVEL_SHIFT) + pattern_key``, ascending (stored in the cache file).
    cell_starts : ndarray of int64, shape (L * KEY_BINS**2 + 1,)
        First row of each (level, bin of r0, bin of r1) cell, index
        ``(level * KEY_BINS + bin0) * KEY_BINS + bin1``: a look-up searches one cell's rows, not
        all of :attr:`keys` (fewer cache misses; stored in the cache file).
    """

    settings: DatabaseSettings
    cat_index: NDArray[np.int64]
    hip: NDArray[np.int64]
    vectors: NDArray[np.float64]
    mag: NDArray[np.float32]
    level_fov_rad: NDArray[np.float64]
    pattern_stars: NDArray[np.unsignedinteger]
    pattern_ratios: NDArray[np.uint16]
    pattern_largest: NDArray[np.uint16]
    level_offsets: NDArray[np.int64]
    verify_levels: NDArray[np.uint16]
    keys: NDArray[np.int64] = field(repr=False, default_factory=lambda: np.zeros(0, np.int64))
    cell_starts: NDArray[np.int64] = field(repr=False, default_factory=lambda: np.zeros(1, np.int64))
    _verify_sets: dict = field(repr=False, compare=False, default_factory=dict)
    _star_tree: list = field(repr=False, compare=False, default_factory=list)

    @property
    def tree(self) -> cKDTree:
        """A KD-tree over :attr:`vectors`, built on first use, then kept (lazily, so that a load
        that never needs it does not pay for building it)."""
        if not self._star_tree:
            self._star_tree.append(cKDTree(self.vectors))
        return self._star_tree[0]

    def verification_stars(self, level: int) -> tuple[cKDTree, NDArray[np.float64], NDArray[np.int64]]:
        """Level ``level``'s verification stars: a KD-tree over their ICRS vectors, the vectors
        (V, 3) and their catalog rows (V,). Built on first use, then kept: querying them costs a
        fraction of filtering every database star around the field."""
        if level not in self._verify_sets:
            bits = self.verify_levels.dtype.type
            members = np.flatnonzero((self.verify_levels >> bits(level)) & bits(1))
            vectors = np.ascontiguousarray(self.vectors[members])
            self._verify_sets[level] = (cKDTree(vectors), vectors, self.cat_index[members])
        return self._verify_sets[level]

    @property
    def n_patterns(self) -> int:
        return int(self.pattern_stars.shape[0])

    @property
    def nbytes(self) -> int:
        """Memory held by the arrays (bytes)."""
        arrays = (self.cat_index, self.hip, self.vectors, self.mag, self.pattern_stars,
                  self.pattern_ratios, self.pattern_largest, self.verify_levels)
        return int(sum(a.nbytes for a in arrays) + self.keys.nbytes)

    def largest_rad(self, rows: NDArray) -> NDArray[np.float64]:
        """Largest edge angle (radians) of the patterns in ``rows``."""
        return largest_from_stored(self.pattern_largest[rows])

    def level_patterns(self, level: int) -> slice:
        return slice(int(self.level_offsets[level]), int(self.level_offsets[level + 1]))


# --- building ---------------------------------------------------------------------------------
def _brightest_near(tree: cKDTree, usable: NDArray[np.bool_], spacing_rad: float,
                    radius_rad: float, count: int) -> list[NDArray[np.int64]]:
    """For sample directions at ``spacing_rad``, the ``count`` brightest usable stars within radius.

    Stars are indexed brightest first, so the brightest are the smallest indices.
    """
    n_points = max(12, int(4.0 * math.pi / spacing_rad**2))
    neighbours = query_cone(tree, fibonacci_sphere(n_points), radius_rad)
    regions = []
    for found in neighbours:
        idx = np.sort(np.asarray(found, dtype=np.int64))
        regions.append(idx[usable[idx]][:count])
    return regions


def _region_patterns(regions: list[NDArray[np.int64]]) -> NDArray[np.int64]:
    """All four-star combinations within each region, deduplicated, shape (P, 4), rows sorted."""
    import itertools

    chunks = []
    by_size: dict[int, list[NDArray]] = {}
    for idx in regions:
        if idx.size >= 4:
            by_size.setdefault(idx.size, []).append(idx)
    for size, groups in by_size.items():
        combos = np.array(list(itertools.combinations(range(size), 4)))
        members = np.stack(groups)  # (G, size), each row ascending
        chunks.append(members[:, combos].reshape(-1, 4))
    if not chunks:
        return np.zeros((0, 4), dtype=np.int64)
    return np.unique(np.concatenate(chunks), axis=0)


def _build_level(vectors: NDArray, tree: cKDTree, doubles: NDArray[np.bool_], fov: float,
                 settings: DatabaseSettings) -> tuple[NDArray, NDArray]:
    """Patterns (P, 4) and verification star indices of one level."""
    radius = settings.region_fraction * fov
    regions = _brightest_near(tree, ~doubles, radius / 2.0, radius, settings.stars_per_region)
    patterns = _region_patterns(regions)
    angles = pair_angles(vectors[patterns])
    patterns = patterns[angles.min(axis=1) >= settings.min_edge_fraction * fov]
    everyone = np.ones(len(vectors), dtype=bool)
    verify = _brightest_near(tree, everyone, fov / 4.0, fov / 2.0, settings.verify_per_region)
    return patterns, np.unique(np.concatenate(verify))


def build_database_arrays(settings: DatabaseSettings,
                          progress: Callable[[int, int], None] | None = None) -> dict[str, NDArray]:
    """Build the database arrays (what is cached); see the module docstring.

    ``progress(done, total)`` is called after each level, for a progress bar.
    """
    catalog = load_catalog()
    mag = catalog.v_mag
    keep = np.flatnonzero(np.isfinite(mag) & (mag <= settings.max_mag))
    keep = keep[np.argsort(mag[keep], kind="stable")]  # brightest first
    sub = catalog.take(keep)
    vectors = sub.vectors(settings.epoch_jyear)
    tree = cKDTree(vectors)
    levels = settings.level_fovs_rad()
    stars_used = np.zeros(len(keep), dtype=bool)
    bits = np.uint16 if len(levels) <= 16 else np.uint32
    verify_bits = np.zeros(len(keep), dtype=bits)
    level_patterns = []
    for k, fov in enumerate(levels):
        doubles = flag_doubles(sub, settings.blend_fraction * fov, settings.blend_delta_mag)
        patterns, verify = _build_level(vectors, tree, doubles, fov, settings)
        level_patterns.append(patterns)
        stars_used[patterns.ravel()] = True
        stars_used[verify] = True
        verify_bits[verify] |= bits(1 << k)
        if progress is not None:
            progress(k + 1, len(levels))
    return _compact(keep, sub, vectors, stars_used, verify_bits, level_patterns, levels)


RATIO_SCALE = 65535.0
"""Edge ratios are stored as uint16: ratio = stored / RATIO_SCALE (resolution 1.5e-5)."""

LARGEST_LN_MIN = math.log(1e-5)
LARGEST_LN_STEP = (math.log(math.pi) - LARGEST_LN_MIN) / 65535.0
"""Largest edges are stored as uint16 on a logarithmic scale, from 1e-5 rad (2 arcsec) to pi:
angle = exp(LARGEST_LN_MIN + stored * LARGEST_LN_STEP), a relative resolution of 1.9e-4 at any
size (a linear scale that reached the 120 deg edges of the widest levels would have been 1.1 %
coarse on the 0.2 deg edges of the narrowest)."""


def largest_to_stored(angle_rad: NDArray) -> NDArray[np.uint16]:
    """Largest edge angles (radians) in stored units (see :data:`LARGEST_LN_STEP`)."""
    ln = np.log(np.clip(angle_rad, math.exp(LARGEST_LN_MIN), math.pi))
    return np.round((ln - LARGEST_LN_MIN) / LARGEST_LN_STEP).astype(np.uint16)


def largest_from_stored(stored: NDArray) -> NDArray[np.float64]:
    """Largest edge angles (radians) from stored units."""
    return np.exp(LARGEST_LN_MIN + np.asarray(stored, dtype=np.float64) * LARGEST_LN_STEP)

KEY_BINS = 64
"""Bins of each of the two smallest ratios in the key (see :func:`pattern_key`)."""


def ratio_bin(quantised: NDArray) -> NDArray[np.int64]:
    """Key bin (0 .. KEY_BINS - 1) of quantised ratios."""
    return (np.asarray(quantised, dtype=np.int64) * KEY_BINS) >> 16


LEVEL_SHIFT = 40
"""Bits below a level's prefix in :attr:`PatternDatabase.keys` (pattern keys are below 2**32)."""


def pattern_key(quantised_ratios: NDArray) -> NDArray[np.int64]:
    """The sort and index key of patterns from their quantised ratios (..., 5).

    ``key = (bin(r0) * KEY_BINS + bin(r1)) * 65536 + r2`` (r2 quantised): sorting by it orders
    patterns by coarse bins of the two smallest ratios and, inside a pair of bins, by the third,
    so one range query per pair of bins returns only patterns whose three smallest
    ratios are all near the image's.
    """
    q = np.asarray(quantised_ratios)[..., :3].astype(np.int64)  # the two other ratios are not in the key
    return (ratio_bin(q[..., 0]) * KEY_BINS + ratio_bin(q[..., 1])) * 65536 + q[..., 2]


def _compact(keep, sub, vectors, stars_used, verify_bits, level_patterns, levels) -> dict[str, NDArray]:
    """Keep only the stars some level uses, renumber, sort each level by :func:`pattern_key`."""
    used = np.flatnonzero(stars_used)
    renumber = np.full(len(keep), -1, dtype=np.int64)
    renumber[used] = np.arange(used.size)
    vec = vectors[used]
    stars, ratios, largest, offsets = [], [], [], [0]
    for patterns in level_patterns:
        local = renumber[patterns]
        r, big = edge_ratios(pair_angles(vec[local]))
        quantised = np.round(r * RATIO_SCALE).astype(np.uint16)
        order = np.argsort(pattern_key(quantised), kind="stable")
        stars.append(local[order].astype(np.uint16 if used.size <= 65536 else np.uint32))
        ratios.append(quantised[order])
        largest.append(largest_to_stored(big[order]))
        offsets.append(offsets[-1] + len(order))
    all_ratios, level_offsets = np.concatenate(ratios), np.array(offsets, dtype=np.int64)
    keys, cell_starts = key_index(all_ratios, level_offsets)
    return {
        "cat_index": keep[used], "hip": sub.hip[used].astype(np.int64), "vectors": vec,
        "mag": sub.v_mag[used].astype(np.float32), "level_fov_rad": levels,
        "pattern_stars": np.concatenate(stars), "pattern_ratios": all_ratios,
        "pattern_largest": np.concatenate(largest), "level_offsets": level_offsets,
        "verify_levels": verify_bits[used], "keys": keys, "cell_starts": cell_starts,
    }


def key_index(pattern_ratios: NDArray[np.uint16],
              level_offsets: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The key index of patterns sorted by level, then :func:`pattern_key`.

    Parameters
    ----------
    pattern_ratios : ndarray of uint16, shape (P, 5)
        Quantised sorted edge ratios (:data:`RATIO_SCALE`).
    level_offsets : ndarray of int, shape (L + 1,)
        Patterns of level k are rows ``level_offsets[k]:level_offsets[k + 1]``.

    Returns
    -------
    keys : ndarray of int64, shape (P,)
        ``(level << LEVEL_SHIFT) + pattern_key``, ascending.
    cell_starts : ndarray of int64, shape (L * KEY_BINS**2 + 1,)
        First row of each (level, bin of r0, bin of r1) cell, then P.
    """
    level = np.repeat(np.arange(len(level_offsets) - 1, dtype=np.int64), np.diff(level_offsets))
    keys = (level << LEVEL_SHIFT) + pattern_key(pattern_ratios)
    cells = np.arange((len(level_offsets) - 1) * KEY_BINS**2, dtype=np.int64)
    cell_keys = ((cells // KEY_BINS**2) << LEVEL_SHIFT) + (cells % KEY_BINS**2) * 65536
    return keys, np.append(np.searchsorted(keys, cell_keys, side="left"), keys.size)


# --- loading ----------------------------------------------------------------------------------
def _from_arrays(settings: DatabaseSettings, arrays: dict[str, NDArray]) -> PatternDatabase:
    return PatternDatabase(
        settings=settings, cat_index=arrays["cat_index"], hip=arrays["hip"], vectors=arrays["vectors"],
        mag=arrays["mag"], level_fov_rad=arrays["level_fov_rad"], pattern_stars=arrays["pattern_stars"],
        pattern_ratios=arrays["pattern_ratios"], pattern_largest=arrays["pattern_largest"],
        level_offsets=arrays["level_offsets"], verify_levels=arrays["verify_levels"], keys=arrays["keys"],
        cell_starts=arrays["cell_starts"])


def load_database(settings: DatabaseSettings | None = None,
                  progress: Callable[[int, int], None] | None = None) -> PatternDatabase:
    """The pattern database for these settings, built into the cache on first use.

    The first call for new settings builds the database (tens of seconds to a few minutes,
    reported by :func:`database_report`); later calls load it from the cache in well under a
    second, and calls in the same process reuse it.
    """
    settings = settings or DatabaseSettings()
    if settings not in _LOADED:
        arrays = cache.load_or_build(DB_KIND, DB_VERSION, asdict(settings),
                                     lambda: build_database_arrays(settings, progress))
        _LOADED[settings] = _from_arrays(settings, arrays)
    return _LOADED[settings]


_LOADED: dict[DatabaseSettings, PatternDatabase] = {}
"""Databases loaded in this process (a few tens of MB each)."""


def is_cached(settings: DatabaseSettings | None = None) -> bool:
    """True when the database for these settings is loaded or its cache file is current.

    The file's header is read (:func:`startrack.cache.is_current`), not just its existence: a
    damaged, stale or old-layout file is rebuilt by :func:`load_database`, so it counts as not
    cached and a caller that announces a rebuild announces it only when one happens.
    """
    settings = settings or DatabaseSettings()
    return settings in _LOADED or cache.is_current(DB_KIND, DB_VERSION, asdict(settings))


def database_path(settings: DatabaseSettings | None = None):
    """Where the cache file of these settings lives (it may not exist yet)."""
    settings = settings or DatabaseSettings()
    return cache.cache_dir() / f"{DB_KIND}-{cache.input_key(DB_KIND, DB_VERSION, asdict(settings))}.npz"


def database_report(settings: DatabaseSettings | None = None) -> dict[str, float | list]:
    """Build (if needed) and load a database, and say what it costs: seconds, bytes, counts,
    and per level (``levels``: [FOV deg, patterns] pairs, narrowest first).

    ``build_s`` is NaN when a valid cache file was already there.
    """
    settings = settings or DatabaseSettings()
    params = asdict(settings)
    build_s = float("nan")
    if cache.load(DB_KIND, DB_VERSION, params) is None:
        t0 = time.perf_counter()
        cache.save(DB_KIND, DB_VERSION, params, build_database_arrays(settings))
        build_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    db = _from_arrays(settings, require(cache.load(DB_KIND, DB_VERSION, params), "the database's cache file"))
    load_s = time.perf_counter() - t0
    return {"build_s": build_s, "load_s": load_s, "file_bytes": database_path(settings).stat().st_size,
            "memory_bytes": db.nbytes, "n_patterns": db.n_patterns, "n_stars": len(db.hip),
            "n_levels": len(db.level_fov_rad),
            "levels": [[float(np.degrees(f)), int(n)] for f, n in zip(db.level_fov_rad, np.diff(db.level_offsets),
                                                                      strict=True)]}
