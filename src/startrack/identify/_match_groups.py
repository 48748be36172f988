"""Lost-in-space identification by match groups: van Bezooijen's algorithm as Jacobs 1995 uses it
(Jacobs 1995, ``Match.mod``, Ch. 3 and App. D; Jacobs 1995 §5.2, §3.5, Tables 3-5/3-6/3-7).

A *match* is one assignment (observed star o, guide star g), stored as the key ``o * S + g`` for
S guide stars.

1. Pair matching (:func:`match_pairs`): for every pair of the brightest observed stars (at most
   8), every guide pair whose angle lies within the distance tolerance, in both orientations,
   keeping an orientation only if both magnitudes match when magnitudes are given.
2. Match groups (:class:`Associations`): every distinct match is a *kernel*; its associated
   matches are the partners of the pairs it occurs in. A kernel's groups take at most one guide
   star per observed star (the Cartesian product of :func:`product_groups`); its confidence is
   the number of observed stars it is associated with.
3. Elimination of small groups (:func:`iclim_start`): for n stars to be recognised, n kernels
   need a confidence of at least n - 1; with the largest such n, ICLim = n - 2 and every kernel
   of confidence <= ICLim is deleted, and removed from the associated lists of the others.
   3b. Geometry test: every two associated matches must fit each other's distance too; a group
   with a misfit pair is split into one without either star (:func:`split_group`). Splitting
   every product group ends, after step 4, in the maximal consistent subsets of the kernel's
   associates; :func:`maximal_groups` finds those directly (Bron-Kerbosch), without building
   the product first. Groups whose confidence is then <= ICLim are dropped.
   3c. Mirror test (:func:`mirror_ok`): the triple product of the kernel and two members has the
   same sign for observed (camera frame) and guide (ICRS) vectors (the notes' recommended form).
4. Redundancy elimination (:func:`unique_groups`): groups with the same set of matches go.
5. Extraction (:func:`largest_group`): the largest group wins; of equal largest groups the one
   with the smallest sum of |d_obs - d_cat| is taken, unless one of them shares no match with it.
   Then (or when no group is left) ICLim is decremented and steps 3-5 repeat, down to ICLim = 1.

The thesis stops there; here the attitude of the group's best-spread three stars is then
confirmed on every image star with the false-match probability of :mod:`._verify`
(:class:`.confirm.Confirmer`), and a group that fails leads on to the next ICLim. The guide stars
are those of a :class:`.pair_database.PairDatabase`, or of a sub-catalogue of it
(:func:`sub_catalogue`, Jacobs 1995 §5.2's ``MakeCat``).
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ..attitude import q_method_quaternions
from ..camera import Camera
from ..catalog import chord_from_angle, load_catalog
from ..errors import InvalidInputError
from ..frames import angle_between, cross
from ..results import Status
from ._candidate import MatchOutcome
from ._confirm import Confirmer, StarSet, match_radius_px
from ._kvector import KVector
from ._options_base import MatcherOptionsBase
from ._pair_database import PairDatabase


@dataclass(frozen=True)
class VanBezooijenOptions(MatcherOptionsBase):
    """Settings of the van Bezooijen matcher.

    Attributes
    ----------
    stars : int
        Brightest image stars matched (the "observed stars"; 8 in Jacobs 1995).
    verify_stars, centroid_sigma_px, match_radius_px, max_false_match_prob, timeout_s
        As for :class:`.pyramid.PyramidOptions`.
    distance_tolerance_rad : float or None
        ``d_uncert``: allowed |d_obs - d_cat| of a pair (radians); None gives
        3 sqrt(2) ``centroid_sigma_px`` / fx.
    mag_tolerance : float
        ``Mv_uncert``: allowed |Mv_obs - Mv_cat| (mag), used when magnitudes are given.
    """

    stars: int = 8
    centroid_sigma_px: float = 0.5
    timeout_s: float = 5.0
    distance_tolerance_rad: float | None = None
    mag_tolerance: float = 0.45

    def __post_init__(self) -> None:
        if not 3 <= self.stars <= 20:
            raise InvalidInputError(f"stars must be 3 to 20 observed stars, got {self.stars}")
        if self.distance_tolerance_rad is not None and not self.distance_tolerance_rad > 0:
            raise InvalidInputError(f"distance_tolerance_rad must be positive, got {self.distance_tolerance_rad}")
        if not self.mag_tolerance >= 0:
            raise InvalidInputError(f"mag_tolerance must be >= 0 mag, got {self.mag_tolerance}")


@dataclass(frozen=True)
class GroupProblem:
    """What the group steps need: observed vectors (n, 3) in the camera frame, guide vectors
    (S, 3) in ICRS, and the distance tolerance (radians) as a function of the angle."""

    obs_vec: NDArray[np.float64]
    guide_vec: NDArray[np.float64]
    tolerance: Callable[[NDArray | float], NDArray | float]

    @cached_property
    def obs_angles(self) -> NDArray[np.float64]:
        """Angles (radians) between every two observed stars, (n, n)."""
        return angle_between(self.obs_vec[:, None], self.obs_vec[None])

    def split(self, keys: NDArray) -> tuple[NDArray, NDArray]:
        """(observed index, guide index) of match keys."""
        return np.divmod(np.asarray(keys, dtype=np.int64), len(self.guide_vec))

    def misfit(self, keys: NDArray) -> NDArray[np.float64]:
        """|d_obs - d_cat| (radians) of every two matches, shape (m, m)."""
        o, g = self.split(keys)
        gd = angle_between(self.guide_vec[g][:, None], self.guide_vec[g][None])
        return np.abs(self.obs_angles[o[:, None], o[None]] - gd)

    def consistent(self, keys: NDArray) -> NDArray[np.bool_]:
        """Whether every two matches fit together (distinct stars, distance within tolerance)."""
        o, g = self.split(keys)
        fits = self.misfit(keys) <= self.tolerance(self.obs_angles[o[:, None], o[None]])
        return fits & (o[:, None] != o[None]) & (g[:, None] != g[None])


def match_pairs(problem: GroupProblem, pdb: PairDatabase, obs_mag: NDArray | None = None,
                guide_mag: NDArray | None = None, mag_tolerance: float = math.inf) -> NDArray[np.int64]:
    """Step 1: every (observed pair, guide pair) whose distances match, as match keys (K, 2).

    Row k holds the two matches of pair k (the thesis's rows 2k-1 and 2k of matcho / matchg);
    both orientations of a guide pair are tried, and with magnitudes (``obs_mag`` (n,),
    ``guide_mag`` (S,)) an orientation is kept only if both stars' magnitudes match.
    """
    n, s = len(problem.obs_vec), len(problem.guide_vec)
    rows = []
    for i, j in itertools.combinations(range(n), 2):
        d = float(angle_between(problem.obs_vec[i], problem.obs_vec[j]))
        tol = float(problem.tolerance(d))
        guide = pdb.pairs_between(d - tol, d + tol).astype(np.int64)
        guide = np.concatenate([guide, guide[:, ::-1]])
        if obs_mag is not None and guide_mag is not None:
            ok = (np.abs(guide_mag[guide[:, 0]] - obs_mag[i]) <= mag_tolerance) & (
                np.abs(guide_mag[guide[:, 1]] - obs_mag[j]) <= mag_tolerance)
            guide = guide[ok]
        rows.append(np.column_stack([i * s + guide[:, 0], j * s + guide[:, 1]]))
    return np.concatenate(rows) if rows else np.zeros((0, 2), dtype=np.int64)


@dataclass(frozen=True)
class Associations:
    """Step 2: the distinct matches (kernels, sorted keys (K,)) and each one's distinct associated
    matches, ``associates[start[k]:start[k + 1]]`` (sorted keys)."""

    kernels: NDArray[np.int64]
    start: NDArray[np.int64]
    associates: NDArray[np.int64]

    @classmethod
    def from_rows(cls, rows: NDArray) -> Associations:
        """From the pair rows (K, 2) of :func:`match_pairs` (each pair associates both ways)."""
        edges = np.unique(np.concatenate([rows, rows[:, ::-1]]).reshape(-1, 2), axis=0)
        kernels, start = np.unique(edges[:, 0], return_index=True)
        return cls(kernels, np.r_[start, len(edges)].astype(np.int64), edges[:, 1])

    def of(self, k: int) -> NDArray[np.int64]:
        """Associated matches of the k-th kernel."""
        return self.associates[self.start[k]:self.start[k + 1]]

    def confidence(self, n_guide: int, alive: NDArray[np.bool_] | None = None) -> NDArray[np.int64]:
        """Each kernel's confidence (K,): the number of observed stars among its associated
        matches, counting only the associates that are ``alive`` kernels (bool (K,)) if given."""
        src = np.repeat(np.arange(len(self.kernels)), np.diff(self.start))
        dst = self.associates
        if alive is not None:
            keep = alive[np.searchsorted(self.kernels, dst)]
            src, dst = src[keep], dst[keep]
        per_star = np.unique(np.column_stack([src, dst // n_guide]), axis=0)
        return np.bincount(per_star[:, 0], minlength=len(self.kernels)).astype(np.int64)


def product_groups(candidates: Sequence[Sequence[int]]) -> list[tuple[int, ...]]:
    """Step 2's groups of one kernel, as ``Match.mod`` builds them: one candidate from each
    observed star that has any (a Cartesian product; empty lists are skipped)."""
    return list(itertools.product(*[c for c in candidates if len(c)]))


def iclim_start(confidences: ArrayLike) -> int:
    """Step 3: ICLim = n - 2 for the largest n with at least n kernels of confidence >= n - 1.

    The n groups must have n different kernels, so kernels are counted (not the copies that the
    Cartesian product makes of one kernel's group). Returns 0 when not even 3 stars can match.
    """
    conf = np.sort(np.asarray(confidences, dtype=np.int64))[::-1]
    ns = np.arange(1, conf.size + 1)
    ok = conf >= ns - 1  # the n-th largest confidence is >= n - 1
    return int(ns[ok].max()) - 2 if np.any(ok) else 0


def split_group(group: Sequence[int], consistent: Callable[[int, int], bool]) -> list[frozenset]:
    """Step 3b as printed: split a group on its first misfit pair (a, b) into one without a and
    one without b, until every group is consistent (Table 3-4). Returns the distinct results."""
    todo, done = [tuple(group)], set()
    while todo:
        members = todo.pop()
        bad = next(((a, b) for a, b in itertools.combinations(members, 2) if not consistent(a, b)), None)
        if bad is None:
            done.add(frozenset(members))
        else:
            todo.extend(tuple(m for m in members if m != drop) for drop in bad)
    return sorted(done, key=lambda s: sorted(s))


def maximal_groups(adjacency: NDArray[np.bool_]) -> list[list[int]]:
    """The maximal sets of mutually consistent matches (Bron-Kerbosch with pivoting).

    ``adjacency`` (m, m) is symmetric with a False diagonal; returns index lists.
    """
    nbr = [sum(1 << int(j) for j in np.flatnonzero(row)) for row in adjacency]
    found: list[int] = []

    def expand(r: int, p: int, x: int) -> None:
        if not p and not x:
            found.append(r)
            return
        pivot = max(_bits(p | x), key=lambda u: (p & nbr[u]).bit_count())
        for v in _bits(p & ~nbr[pivot]):
            expand(r | 1 << v, p & nbr[v], x & nbr[v])
            p &= ~(1 << v)
            x |= 1 << v

    expand(0, (1 << len(nbr)) - 1, 0)
    return [_bits(r) for r in found]


def _bits(mask: int) -> list[int]:
    return [i for i in range(mask.bit_length()) if mask >> i & 1]


def mirror_ok(obs_vec: NDArray, guide_vec: NDArray) -> bool:
    """Step 3c: kernel (row 0) and the two members of largest observed triple product must turn
    the same way round in the camera frame and in ICRS (vectors (m, 3); m < 3 passes)."""
    if len(obs_vec) < 3:
        return True
    a, b = np.triu_indices(len(obs_vec) - 1, 1)
    t_obs = np.einsum("i,ni->n", obs_vec[0], cross(obs_vec[a + 1], obs_vec[b + 1]))
    k = int(np.argmax(np.abs(t_obs)))
    return bool(t_obs[k] * np.dot(guide_vec[0], np.cross(guide_vec[a[k] + 1], guide_vec[b[k] + 1])) >= 0)


def unique_groups(groups: Sequence[frozenset]) -> list[frozenset]:
    """Step 4: each set of matches once, in order of first appearance."""
    return list(dict.fromkeys(groups))


def largest_group(groups: Sequence[frozenset], quality: Callable[[frozenset], float]) -> frozenset | None:
    """Step 5: the largest group; of equal largest groups the one of smallest ``quality`` (sum of
    |d_obs - d_cat|). None when there is none, or when a largest group shares no match with it
    (the thesis's "share no common matches"; sharing two or more, "any one will do", leaves sharing
    exactly one undefined: it is accepted here, the confirmation judging it)."""
    if not groups:
        return None
    size = max(len(g) for g in groups)
    top = sorted((g for g in groups if len(g) == size), key=quality)
    if any(not top[0] & other for other in top[1:]):
        return None
    return top[0]


def kernel_groups(problem: GroupProblem, kernel: int, members: NDArray) -> list[frozenset]:
    """Steps 3b-3c for one kernel: its maximal consistent groups (kernel and associated matches,
    keys) that pass the mirror test."""
    groups = []
    for clique in maximal_groups(problem.consistent(members)):
        keys = np.concatenate([[kernel], members[clique]])
        o, g = problem.split(keys)
        if mirror_ok(problem.obs_vec[o], problem.guide_vec[g]):
            groups.append(frozenset(keys.tolist()))
    return groups


def _level_groups(problem: GroupProblem, assoc: Associations, conf: NDArray, level: int, deadline: float,
                  memo: dict) -> list[frozenset]:
    """Steps 3-4 at one ICLim: the consistent, unmirrored groups of confidence > ``level``
    (``memo`` keeps each kernel's groups for its list of associates across levels)."""
    alive = conf > level
    alive_assoc = alive[np.searchsorted(assoc.kernels, assoc.associates)]
    groups: list[frozenset] = []
    for k in np.flatnonzero(alive & (assoc.confidence(len(problem.guide_vec), alive) > level)):
        members = assoc.of(int(k))[alive_assoc[assoc.start[k]:assoc.start[k + 1]]]
        key = (int(k), members.tobytes())
        if key not in memo:
            memo[key] = kernel_groups(problem, int(assoc.kernels[k]), members)
        groups.extend(g for g in memo[key] if len(g) - 1 > level)
        if time.perf_counter() > deadline:
            break
    return unique_groups(groups)


def candidate_groups(problem: GroupProblem, rows: NDArray, deadline: float) -> Iterator[tuple[NDArray, int]]:
    """Steps 2-5: the recognised group of each ICLim, from the first down to 1, each once, with
    the number of groups generated so far (match keys (m,), count)."""
    assoc = Associations.from_rows(rows)
    conf = assoc.confidence(len(problem.guide_vec))
    n_groups, tried = 0, set()
    memo: dict[tuple[int, bytes], list[frozenset]] = {}

    def quality(group: frozenset) -> float:
        return float(np.triu(problem.misfit(np.array(sorted(group)))).sum())

    for level in range(iclim_start(conf), 0, -1):
        groups = _level_groups(problem, assoc, conf, level, deadline, memo)
        n_groups += len(groups)
        best = largest_group(groups, quality)
        if best is not None and best not in tried:
            tried.add(best)
            yield np.array(sorted(best), dtype=np.int64), n_groups
        if time.perf_counter() > deadline:
            return


def best_triple(obs_vec: NDArray) -> NDArray[np.int64]:
    """Indices of the three vectors (m >= 3, 3) with the largest |triple product| (best spread)."""
    trip = np.array(list(itertools.combinations(range(len(obs_vec)), 3)))
    vol = np.abs(np.einsum("ni,ni->n", obs_vec[trip[:, 0]], cross(obs_vec[trip[:, 1]], obs_vec[trip[:, 2]])))
    return trip[int(np.argmax(vol))]


def match_van_bezooijen(x: ArrayLike, y: ArrayLike, camera: Camera, pdb: PairDatabase, *,
                        focal_tolerance: float = 0.0, options: VanBezooijenOptions | None = None,
                        magnitudes: ArrayLike | None = None) -> MatchOutcome:
    """Identify image stars with a known camera by van Bezooijen's match groups (Jacobs 1995 §3).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Star positions (our pixel convention), brightest first.
    camera : Camera
        The camera (its focal length known to ``focal_tolerance``).
    pdb : PairDatabase
        Guide stars and their pair directory for (at least) this camera's diagonal FOV; a
        :func:`sub_catalogue` to search only part of the sky.
    focal_tolerance : float
        Relative focal-length uncertainty; widens the distance tolerance by this fraction of the
        angle and lets the confirmation refit the focal length.
    options : VanBezooijenOptions, optional
    magnitudes : array_like, shape (N,), optional
        Estimated visual magnitude of each star (Johnson V, as the catalog's); enables the
        magnitude match with ``options.mag_tolerance``.

    Returns
    -------
    MatchOutcome
        OK with the confirmed candidate; TOO_FEW_STARS (fewer than 3 stars), NO_MATCH (no group
        recognised and confirmed down to ICLim = 1, e.g. a mirrored image or only false stars)
        or TIMEOUT.
    """
    options = options or VanBezooijenOptions()
    x, y = np.asarray(x, dtype=float).ravel(), np.asarray(y, dtype=float).ravel()
    mags = _checked_magnitudes(magnitudes, x.size)
    if x.size < 3:
        return MatchOutcome(Status.TOO_FEW_STARS, f"match groups need at least 3 stars, got {x.size}", None, 0)
    n = min(x.size, options.stars)
    d_uncert = options.distance_tolerance_rad or 3.0 * math.sqrt(2.0) * options.centroid_sigma_px / camera.fx
    problem = GroupProblem(camera.pixel_to_vector(x[:n], y[:n]), pdb.vectors,
                           lambda angle: d_uncert + focal_tolerance * np.asarray(angle))
    guide_mag = None if mags is None else load_catalog().v_mag[pdb.catalog_rows]
    rows = match_pairs(problem, pdb, None if mags is None else mags[:n], guide_mag, options.mag_tolerance)
    confirmer = Confirmer(x, y, match_radius_px(camera, options.match_radius_px), options.verify_stars,
                          options.max_false_match_prob, fit_focal=focal_tolerance > 0)
    stars = StarSet(pdb.tree, pdb.vectors, pdb.catalog_rows)
    deadline, n_groups = time.perf_counter() + options.timeout_s, 0
    for group, n_groups in candidate_groups(problem, rows, deadline):
        o, g = problem.split(group)
        triple = best_triple(problem.obs_vec[o])
        quat = q_method_quaternions(problem.obs_vec[o[triple]][None], pdb.vectors[g[triple]][None],
                                    np.full((1, 3), 1 / 3))[0]
        found = confirmer.confirm(stars, Rotation.from_quat(quat), camera, o[triple], n_groups)
        if found is not None:
            return MatchOutcome(Status.OK, "", found, n_groups)
    if time.perf_counter() > deadline:
        return MatchOutcome(Status.TIMEOUT, f"no match within the {options.timeout_s:g} s time limit", None, n_groups)
    return MatchOutcome(Status.NO_MATCH, f"no match group of the {n} brightest stars was recognised and confirmed",
                        None, n_groups)


def _checked_magnitudes(magnitudes, n: int) -> NDArray | None:
    if magnitudes is None:
        return None
    mags = np.asarray(magnitudes, dtype=float).ravel()
    if mags.shape != (n,) or not np.all(np.isfinite(mags)):
        raise InvalidInputError(f"magnitudes must be {n} finite values (one per star), got shape {mags.shape}")
    return mags


def sub_catalogue(pdb: PairDatabase, keep: ArrayLike) -> PairDatabase:
    """The guide stars of ``keep`` (bool, shape (S,)) and their pairs: Jacobs 1995's sub-catalogue
    (§5.2, ``MakeCat`` + ``DistTab``), e.g. the stars of :func:`region_mask`."""
    keep = np.asarray(keep, dtype=bool)
    if keep.shape != (len(pdb.vectors),):
        raise InvalidInputError(f"keep must be a bool mask of the {len(pdb.vectors)} guide stars, got {keep.shape}")
    new_index = np.cumsum(keep) - 1
    both = keep[pdb.pairs[:, 0]] & keep[pdb.pairs[:, 1]]
    angles = pdb.angles[both]
    vectors = pdb.vectors[keep]
    return PairDatabase(pdb.settings, pdb.catalog_rows[keep], vectors, new_index[pdb.pairs[both]].astype(np.int32),
                        angles, KVector.build(angles), cKDTree(vectors))


def region_mask(pdb: PairDatabase, boresights: ArrayLike, radius_rad: float) -> NDArray[np.bool_]:
    """Guide stars within ``radius_rad`` of any of the ICRS unit vectors ``boresights`` (B, 3):
    the area a set of sampled attitudes covers (``MakeCat`` marks 1 deg blocks; this marks cones)."""
    centres = np.atleast_2d(np.asarray(boresights, dtype=float))
    if centres.ndim != 2 or centres.shape[1] != 3 or not 0 < radius_rad < math.pi:
        raise InvalidInputError("boresights must be unit vectors (B, 3) and radius_rad in (0, pi)")
    dist, _ = cKDTree(centres).query(pdb.vectors, distance_upper_bound=chord_from_angle(radius_rad, "radius_rad"))
    return np.isfinite(dist)
