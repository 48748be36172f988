"""Lost-in-space identification by triangle area and polar moment, planar (Cole & Crassidis 2006)
or spherical (Cole & Crassidis 2004), as Huffman 2006 §5.4.2 describes them,
for a camera whose focal length is known (to a few percent at most).

Candidate catalog triangles come from a **triangle directory** (:mod:`._triangle_database`: every
catalog triangle of the pair directory's stars, sorted by area with a k-vector), not from the pair
directory: one k-vector query on the area and a vectorised moment test per image triangle. On
15-deg fields this is about as fast as deriving triangles from pairs, and it is the method as
published; the directory is built once into the user cache (the spherical one takes longer).

1. Triads of the brightest image stars in Mortari's order (:func:`.star_order.ordered_star_sets`).
2. The image triangle's area A and polar moment I (:mod:`._triangle_features`), with 1-sigma errors
   by linearised propagation of the centroid noise (``centroid_sigma_px / fx`` per axis and star);
   candidates are the catalog triangles with ``|A_cat - A| <= k sigma_A`` and
   ``|I_cat - I| <= k sigma_I`` (k = ``sigma_k``; widened by the focal-length uncertainty).
3. The vertex correspondence: the orderings of each candidate with the image's handedness whose
   three sides fit the image's within tolerance (a mirror image is refused here).
4. When several candidates remain, pivoting (§5.4.2): a further image star l forms the triangle
   (i, j, l); only candidates whose stars i, j appear in one of its matches are kept, extended by
   its third star (:func:`.pair_search.pivot`).
5. The rotation (q-method) of the unique candidate, confirmed with :mod:`._confirm`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import NDArray

from ..camera import Camera
from ..frames import angle_between
from ._candidate import MatchOutcome
from ._pair_database import PairDatabase
from ._pair_search import PairSearchOptions, PatternMatcher, SearchContext, handedness, join_rows, search
from ._triangle_database import TriangleDatabase, load_triangle_database
from ._triangle_features import check_variant, feature_sigmas, triangle_features


@dataclass(frozen=True)
class TriangleOptions(PairSearchOptions):
    """Settings of the triangle matcher (see :class:`.pair_search.PairSearchOptions`)."""


ORDERINGS = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]])
"""The six vertex orders of a catalog triangle: three of each handedness."""
PARITY = np.array([1, 1, 1, -1, -1, -1])
"""+1 for the orders that keep the handedness of the stored triangle."""
_SIDE_OF = {(0, 1): 0, (0, 2): 1, (1, 2): 2}
SIDES = np.array([[_SIDE_OF[tuple(sorted((p[a], p[b])))] for a, b in ((0, 1), (0, 2), (1, 2))] for p in ORDERINGS])
"""For each order, which stored side (0-1, 0-2, 1-2) becomes its side i-j, i-k, j-k."""


def feature_window(ctx: SearchContext, img_vec: NDArray, variant: str) -> tuple[float, float, float, float]:
    """(area, moment, area half-width, moment half-width) of an image triangle (3, 3)."""
    area, moment = triangle_features(img_vec, variant)
    sigma_area, sigma_moment = feature_sigmas(img_vec, ctx.sigma_rad, variant)
    scale = 1.0 + ctx.focal_tolerance  # angles scale with the focal length; area as its square
    return (float(area), float(moment), ctx.sigma_k * sigma_area + (scale**2 - 1.0) * float(area),
            ctx.sigma_k * sigma_moment + (scale**4 - 1.0) * float(moment))


def oriented_matches(ctx: SearchContext, cand: NDArray, img_vec: NDArray) -> NDArray[np.int64]:
    """Ordered catalog triples (R, 3) of unordered candidates (T, 3) whose sides (i-j, i-k, j-k)
    fit the image triangle's within tolerance and whose handedness is the image's."""
    cat = ctx.pdb.vectors[cand]
    sides = angle_between(cat[:, [0, 0, 1]], cat[:, [1, 2, 2]])  # (T, 3): 0-1, 0-2, 1-2
    img_angle = angle_between(img_vec[[0, 0, 1]], img_vec[[1, 2, 2]])
    fits = np.all(np.abs(sides[:, SIDES] - img_angle) <= ctx.tolerance(img_angle), axis=2)  # (T, 6)
    fits &= handedness(cat)[:, None] * PARITY == handedness(img_vec)
    tri, order = np.nonzero(fits)
    return cand[tri[:, None], ORDERINGS[order]].astype(np.int64)


def triangle_candidates(tdb: TriangleDatabase, ctx: SearchContext, img: tuple[int, ...]) -> NDArray[np.int64]:
    """Catalog stars (R, 3) matching image stars ``img`` (three) by area, moment and sides."""
    img_vec = ctx.vec[list(img)]
    area, moment, d_area, d_moment = feature_window(ctx, img_vec, tdb.variant)
    part = tdb.between(area - d_area, area + d_area)
    fits = np.abs(tdb.moment[part] - moment) <= d_moment
    return oriented_matches(ctx, tdb.triangles[part][fits], img_vec)


def extend_by_triangle(tdb: TriangleDatabase, ctx: SearchContext, table: NDArray, img: tuple[int, ...],
                       new: int) -> NDArray[np.int64]:
    """Pivot: the matches of triangle (img[0], img[1], new) that share their first two stars with a row."""
    return join_rows(table, [0, 1], triangle_candidates(tdb, ctx, (img[0], img[1], new)))


def match_triangles(x: NDArray, y: NDArray, camera: Camera, pdb: PairDatabase, *, focal_tolerance: float = 0.0,
                    options: TriangleOptions | None = None, variant: str = "planar") -> MatchOutcome:
    """Identify image stars with a known camera by triangle area and polar moment.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Star positions (our pixel convention), brightest first.
    camera : Camera
        The camera (its focal length is taken as known to ``focal_tolerance``).
    pdb : PairDatabase
        A directory for (at least) this camera's diagonal field of view; its triangle directory
        is loaded with :func:`.triangle_database.load_triangle_database` (built on first use).
    focal_tolerance : float
        Relative uncertainty of the focal length; widens the tolerances and lets the confirmation
        refit the focal length.
    options : TriangleOptions, optional
    variant : {"planar", "spherical"}
        Chord-triangle (Heron) or spherical-triangle (L'Huilier) features.

    Returns
    -------
    MatchOutcome
        ``Status.OK`` with the confirmed candidate; ``TOO_FEW_STARS`` below 4 stars; ``NO_MATCH``
        or ``TIMEOUT`` otherwise (mirrored or false star lists end there).
    """
    tdb = load_triangle_database(pdb, check_variant(variant))
    matcher = PatternMatcher(f"{variant}-triangle matcher", 3, partial(triangle_candidates, tdb),
                             partial(extend_by_triangle, tdb))
    return search(matcher, x, y, camera, pdb, focal_tolerance, options or TriangleOptions())
