"""Lost-in-space identification by the angle method with pivoting (Huffman 2006 §5.4.1),
for a camera whose focal length is known (to a few percent at most).

1. Pairs of the brightest image stars in the generalised Pyramid order
   (:func:`.star_order.ordered_star_sets` with sets of two).
2. Every catalog pair of the directory whose angle fits the image pair (k-vector range query),
   both ways round: the candidate correspondences of the two stars.
3. Pivoting: a further image star s3 is paired with the first star s1; the catalog pairs of
   (s1, s3) that share their first star with a candidate keep it, extended by their second star
   (which must also fit the angle s2-s3 and the handedness of s1, s2, s3). Further stars are
   added until one correspondence is left (:func:`.pair_search.pivot`).
4. Its rotation (q-method on all its stars) is confirmed with :mod:`._confirm`.

Unlike the Pyramid, no attitude is tried before the pivots have made the correspondence unique.
"""

from __future__ import annotations

from dataclasses import dataclass

from numpy.typing import NDArray

from ..camera import Camera
from ._candidate import MatchOutcome
from ._pair_database import PairDatabase
from ._pair_search import PairSearchOptions, PatternMatcher, SearchContext, extend_by_angle, search


@dataclass(frozen=True)
class AnglePivotOptions(PairSearchOptions):
    """Settings of the angle-pivot matcher (see :class:`.pair_search.PairSearchOptions`)."""

    max_pivots: int = 5


def _pair_candidates(ctx: SearchContext, img: tuple[int, ...]) -> NDArray:
    """Catalog pairs (K, 2) for image pair ``img``, both ways round."""
    return ctx.pairs_fitting(img[0], img[1])


ANGLE_PIVOT = PatternMatcher("angle-pivot matcher", 2, _pair_candidates, extend_by_angle)


def match_angle_pivot(x: NDArray, y: NDArray, camera: Camera, pdb: PairDatabase, *, focal_tolerance: float = 0.0,
                      options: AnglePivotOptions | None = None) -> MatchOutcome:
    """Identify image stars with a known camera by pair angles and pivoting.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Star positions (our pixel convention), brightest first.
    camera : Camera
        The camera (its focal length is taken as known to ``focal_tolerance``).
    pdb : PairDatabase
        A directory for (at least) this camera's diagonal field of view.
    focal_tolerance : float
        Relative uncertainty of the focal length; widens the angle tolerance and lets the
        confirmation refit the focal length.
    options : AnglePivotOptions, optional

    Returns
    -------
    MatchOutcome
        ``Status.OK`` with the confirmed candidate; ``TOO_FEW_STARS`` below 4 stars; ``NO_MATCH``
        or ``TIMEOUT`` otherwise (mirrored or false star lists end there).
    """
    return search(ANGLE_PIVOT, x, y, camera, pdb, focal_tolerance, options or AnglePivotOptions())
