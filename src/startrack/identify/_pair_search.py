"""The search loop shared by the pivoting matchers on the star-pair directory (angle method with
pivoting, Cole & Crassidis triangles, the n-vertex match;
Huffman 2006 §5.4.1, §5.5.2, §5.4.2-1.21, 1.23).

A matcher supplies, for a set of image stars, a *table* of catalog stars: one row per candidate
correspondence, one column per image star of the set. The loop here

1. takes sets of the brightest image stars in the generalised Pyramid order
   (:func:`.star_order.ordered_star_sets`);
2. while the table has several rows (or fewer than three columns), *pivots* on a further image
   star (Huffman 2006 §5.4.1): the matcher's ``extend`` joins the table with the new star's
   candidates on the stars they share, then the new star's angles to every star of the row and
   the handedness of the first two and the new star must fit the image
   (:func:`consistent_rows`). A pivot star that empties the table is taken as false or missing
   and skipped; at most ``max_pivots`` further stars are tried;
3. fits the rotation of each remaining row (q-method) and confirms it with :mod:`._confirm`
   (binomial false-match probability of :mod:`._verify`), the pivot stars counting as pattern
   stars. With an uncertain focal length (``focal_tolerance > 0``) the angles of a row share one
   fitted scale factor, which both tightens the pivot test and rescales the focal length of the
   hypothesis before confirmation (:func:`hypothesis`); a compact pattern's rotation with a
   focal length 2 % off would miss the stars at the image's edges.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..attitude import q_method_quaternions
from ..camera import Camera
from ..frames import angle_between, cross
from ..results import Status
from ._candidate import MatchOutcome
from ._confirm import Confirmer, StarSet, match_radius_px
from ._options_base import MatcherOptionsBase
from ._pair_database import PairDatabase
from ._star_order import further_stars, ordered_star_sets


@dataclass(frozen=True)
class PairSearchOptions(MatcherOptionsBase):
    """Settings shared by the pivoting matchers (the first six as :class:`.pyramid.PyramidOptions`).

    Attributes
    ----------
    stars : int
        Brightest image stars used to form patterns and pivots.
    verify_stars : int
        Brightest image stars tested in the confirmation.
    centroid_sigma_px : float
        1-sigma centroid error per axis (pixels); sets the angle tolerance.
    match_radius_px : float or None
        Confirmation radius (default: :func:`.confirm.match_radius_px`).
    max_false_match_prob : float
    timeout_s : float
    max_pivots : int
        Further stars tried per pattern while its correspondence is not unique.
    max_confirm : int
        Rows still confirmed one by one when pivoting leaves several; a pattern with more is dropped.
    sigma_k : float
        Tolerances are ``sigma_k`` standard deviations (3 as in the Pyramid).
    """

    stars: int = 12
    centroid_sigma_px: float = 0.5
    timeout_s: float = 5.0
    max_pivots: int = 4
    max_confirm: int = 6
    sigma_k: float = 3.0


@dataclass(frozen=True)
class SearchContext:
    """What a matcher's candidate functions need: the image stars as camera-frame unit vectors
    (N, 3), the directory, the 1-sigma angle error of one star per axis (radians) and the
    relative focal-length uncertainty."""

    vec: NDArray[np.float64]
    pdb: PairDatabase
    sigma_rad: float
    sigma_k: float
    focal_tolerance: float

    def tolerance(self, angle):
        """Allowed error (radians) of an inter-star angle: ``sigma_k`` sigmas of the difference of
        two stars' errors plus the focal-length scale error."""
        return self.sigma_k * math.sqrt(2.0) * self.sigma_rad + self.focal_tolerance * angle

    pair_cache: dict[tuple[int, int, bool], NDArray[np.int32]] = field(default_factory=dict, repr=False)

    def pairs_fitting(self, i: int, j: int, both_ways: bool = True) -> NDArray[np.int32]:
        """Catalog pairs (K, 2) whose angle fits image stars i and j (k-vector range query), each
        pair also the other way round (2K, 2) when ``both_ways``. Kept for the next set that
        has the same two stars."""
        key = (min(i, j), max(i, j), both_ways)
        if key not in self.pair_cache:
            angle = float(angle_between(self.vec[i], self.vec[j]))
            tol = self.tolerance(angle)
            pairs = self.pdb.pairs_between(angle - tol, angle + tol)
            self.pair_cache[key] = np.concatenate([pairs, pairs[:, ::-1]]) if both_ways else pairs
        return self.pair_cache[key]


Candidates = Callable[[SearchContext, tuple[int, ...]], NDArray[np.int64]]
"""(context, image star set) -> table (T, len(set)) of catalog star indices."""
Extend = Callable[[SearchContext, NDArray[np.int64], tuple[int, ...], int], NDArray[np.int64]]
"""(context, table (T, m), its image stars, new image star) -> joined table (T', m + 1), unfiltered."""


def expand_ranges(lo: NDArray[np.int64], hi: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """For ranges [lo[r], hi[r]): (r, index) of every member, flattened (a vectorised double loop)."""
    count = hi - lo
    owner = np.repeat(np.arange(len(lo)), count)
    index = np.repeat(lo, count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    return owner, index


def join_rows(table: NDArray, columns: list[int], cand: NDArray) -> NDArray[np.int64]:
    """Rows of ``table`` (T, m) extended by the last column of every row of ``cand`` (R, len(columns) + 1)
    whose first columns equal ``table[:, columns]``; rows that repeat a star are dropped."""
    if len(table) == 0 or len(cand) == 0:
        return np.zeros((0, table.shape[1] + 1), dtype=np.int64)
    base = int(max(table.max(), cand.max())) + 1
    weights = base ** np.arange(len(columns), dtype=np.int64)
    t_key = table[:, columns].astype(np.int64) @ weights
    c_key = cand[:, :-1].astype(np.int64) @ weights
    order = np.argsort(c_key, kind="stable")
    c_key = c_key[order]
    owner, index = expand_ranges(np.searchsorted(c_key, t_key, "left"), np.searchsorted(c_key, t_key, "right"))
    joined = np.column_stack([table[owner], cand[order[index], -1]]).astype(np.int64)
    return joined[np.all(joined[:, :-1] != joined[:, -1:], axis=1)]


def handedness(vectors: NDArray) -> NDArray:
    """Sign of the triple product of three unit vectors (..., 3, 3): +1 counter-clockwise, -1 mirrored."""
    vectors = np.asarray(vectors)
    return np.sign(np.sum(cross(vectors[..., 0, :], vectors[..., 1, :]) * vectors[..., 2, :], axis=-1))


def _edges(img: tuple[int, ...], all_edges: bool) -> tuple[NDArray, NDArray]:
    """Column pairs (u, v) of a row's angles: all of them, or those of the last star."""
    if all_edges:
        return np.triu_indices(len(img), 1)
    return np.arange(len(img) - 1), np.full(len(img) - 1, len(img) - 1)


def angle_scale(ctx: SearchContext, cat_angle: NDArray, img_angle: NDArray) -> NDArray:
    """Least-squares factor s (T,) with image angles ~ s * catalog angles (T, E); the image's
    focal length is then ``s`` times the one assumed (angles scale as 1 / focal length)."""
    return (cat_angle @ img_angle) / np.sum(cat_angle**2, axis=1)


def consistent_rows(ctx: SearchContext, table: NDArray, img: tuple[int, ...]) -> NDArray[np.bool_]:
    """Rows of ``table`` (T, m) whose angles fit the image's and, for m >= 3, whose stars (first,
    second, last) have the image's handedness.

    With a known focal length, each angle from the last star must fit within
    :meth:`SearchContext.tolerance`. With an uncertain one, all angles of a row share one scale
    factor: it is fitted per row (:func:`angle_scale`, within ``1 +- focal_tolerance``) and every
    scaled angle must then fit within the noise part of the tolerance, so that a false star does
    not ride on the wide focal-length margin.
    """
    cat = ctx.pdb.vectors[table]
    u, v = _edges(img, ctx.focal_tolerance > 0)
    img_angle = angle_between(ctx.vec[np.asarray(img)[u]], ctx.vec[np.asarray(img)[v]])
    cat_angle = angle_between(cat[:, u], cat[:, v])
    if ctx.focal_tolerance > 0:
        scale = angle_scale(ctx, cat_angle, img_angle)
        residual = np.abs(scale[:, None] * cat_angle - img_angle)
        ok = (np.abs(scale - 1.0) <= ctx.focal_tolerance) & np.all(residual <= ctx.tolerance(0.0), axis=1)
    else:
        ok = np.all(np.abs(cat_angle - img_angle) <= ctx.tolerance(img_angle), axis=1)
    if len(img) >= 3:
        ok &= handedness(cat[:, [0, 1, -1]]) == handedness(ctx.vec[[img[0], img[1], img[-1]]])
    return ok


def hypothesis(ctx: SearchContext, camera: Camera, x: NDArray, y: NDArray, row: NDArray,
               used: tuple[int, ...]) -> tuple[Rotation, Camera]:
    """rot_cam_from_icrs (q-method) and camera of one correspondence; with an uncertain focal
    length the camera's focal length is first rescaled by the row's :func:`angle_scale`."""
    vec, ref = ctx.vec[list(used)], ctx.pdb.vectors[row]
    if ctx.focal_tolerance > 0:
        u, v = _edges(used, True)
        scale = angle_scale(ctx, angle_between(ref[u], ref[v])[None], angle_between(vec[u], vec[v]))[0]
        camera = camera.with_focal(camera.fx * float(np.clip(scale, 1 - ctx.focal_tolerance,
                                                               1 + ctx.focal_tolerance)))
        vec = camera.pixel_to_vector(x[list(used)], y[list(used)])
    weights = np.full((1, len(vec)), 1.0 / len(vec))
    return Rotation.from_quat(q_method_quaternions(vec[None], ref[None], weights)[0]), camera


def extend_by_angle(ctx: SearchContext, table: NDArray, img: tuple[int, ...], new: int) -> NDArray[np.int64]:
    """Pivot on the first star of the set (Huffman 2006 §5.4.1): the catalog pairs of image pair
    (img[0], new) that share their first star with a row."""
    return join_rows(table, [0], ctx.pairs_fitting(img[0], new))


def pivot(ctx: SearchContext, table: NDArray, img: tuple[int, ...], further: list[int], extend: Extend,
          max_pivots: int) -> tuple[NDArray, tuple[int, ...]]:
    """Add further image stars to a table until it has one row and three stars (or none are left)."""
    for new in further[:max_pivots]:
        if len(table) == 0 or (len(table) == 1 and len(img) >= 3):
            break
        joined = extend(ctx, table, img, new)
        joined = joined[consistent_rows(ctx, joined, (*img, new))]
        if len(joined):
            table, img = joined, (*img, new)
    return table, img


@dataclass(frozen=True)
class PatternMatcher:
    """One pivoting matcher: its name, the size of its first set, and its candidate functions."""

    name: str
    size: int
    candidates: Candidates
    extend: Extend = extend_by_angle


def search(matcher: PatternMatcher, x: NDArray, y: NDArray, camera: Camera, pdb: PairDatabase,
           focal_tolerance: float, options: PairSearchOptions) -> MatchOutcome:
    """Run a matcher over the image stars (see the module docstring); the result as :func:`.pyramid.match_pyramid`."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if len(x) < max(4, matcher.size):
        return MatchOutcome(Status.TOO_FEW_STARS, f"the {matcher.name} needs at least {max(4, matcher.size)} "
                            f"stars, got {len(x)}", None, 0)
    ctx = SearchContext(camera.pixel_to_vector(x, y), pdb, options.centroid_sigma_px / camera.fx, options.sigma_k,
                        focal_tolerance)
    confirmer = Confirmer(x, y, match_radius_px(camera, options.match_radius_px), options.verify_stars,
                          options.max_false_match_prob, fit_focal=focal_tolerance > 0)
    stars = StarSet(pdb.tree, pdb.vectors, pdb.catalog_rows)
    n = min(len(x), options.stars)
    deadline, trials = time.perf_counter() + options.timeout_s, 0
    for img in ordered_star_sets(matcher.size, n):
        table = matcher.candidates(ctx, img)
        table, used = pivot(ctx, table, img, further_stars(img, n), matcher.extend, options.max_pivots)
        if len(used) >= 3 and len(table) <= options.max_confirm:
            for row in table:
                trials += 1
                found = confirmer.confirm(stars, *hypothesis(ctx, camera, x, y, row, used), np.array(used), trials)
                if found is not None:
                    return MatchOutcome(Status.OK, "", found, trials)
        if time.perf_counter() > deadline:
            return MatchOutcome(Status.TIMEOUT, f"no match within the {options.timeout_s:g} s time limit", None, trials)
    return MatchOutcome(Status.NO_MATCH, f"no {matcher.size}-star pattern of the {n} brightest stars matched the "
                        f"catalog ({trials} candidates tried)", None, trials)

