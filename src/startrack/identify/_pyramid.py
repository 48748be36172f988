"""Lost-in-space identification by triangles on the star-pair directory: the Pyramid of Mortari,
Junkins & Samaan (2001), as Huffman 2006 §5.4-5.5 (§5.5.2, §5.5.4) and Samaan 2002 use it, for a
camera whose focal length is known (to a few percent at most).

1. Triads of the brightest image stars in Mortari's order (:func:`pyramid_triads`), which
   changes stars as fast as possible so one missing or false star does not stall the search.
2. For each edge, the catalog pairs whose angle fits (k-vector range query); triangles are the
   pairs of edges i-j and i-k that share their first star and whose third edge j-k fits too.
3. The handedness of the triangle must match the image's (a mirror image is refused here).
4. The rotation of the three stars (q-method), then the confirmation of the Pyramid's fourth and
   further stars against the directory's stars, with the false-match probability of
   :mod:`._verify` (:mod:`._confirm`).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..attitude import q_method_quaternions
from ..camera import Camera
from ..frames import angle_between
from ..results import Status
from ._candidate import MatchOutcome
from ._confirm import Confirmer, StarSet, match_radius_px
from ._options_base import MatcherOptionsBase
from ._pair_database import PairDatabase


@dataclass(frozen=True)
class PyramidOptions(MatcherOptionsBase):
    """Settings of the Pyramid matcher (:class:`.options_base.MatcherOptionsBase` has the shared ones)."""

    stars: int = 12
    centroid_sigma_px: float = 0.5
    timeout_s: float = 5.0


def pyramid_triads(n: int) -> Iterator[tuple[int, int, int]]:
    """Triads of ``n`` stars (0 = brightest) in Mortari's Pyramid order (Huffman 2006 §5.5.2)."""
    for dj in range(1, n - 1):
        for dk in range(1, n - dj):
            for i in range(n - dj - dk):
                yield i, i + dj, i + dj + dk


def _oriented(pairs: NDArray) -> NDArray:
    """Each pair both ways round, shape (2K, 2)."""
    return np.concatenate([pairs, pairs[:, ::-1]])


def candidate_triangles(img_vec: NDArray, pdb: PairDatabase, tolerance) -> NDArray[np.int64]:
    """Catalog star triples (T, 3) whose three angles and handedness fit an image triangle.

    Parameters
    ----------
    img_vec : ndarray, shape (3, 3)
        Camera-frame unit vectors of image stars i, j, k.
    tolerance : callable(angle) -> angle
        Allowed angle error (radians) for an edge of that angle.
    """
    a_ij, a_ik, a_jk = angle_between(img_vec[[0, 0, 1]], img_vec[[1, 2, 2]])
    ij = _oriented(pdb.pairs_between(a_ij - tolerance(a_ij), a_ij + tolerance(a_ij)))
    ik = _oriented(pdb.pairs_between(a_ik - tolerance(a_ik), a_ik + tolerance(a_ik)))
    if ij.size == 0 or ik.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    ik = ik[np.argsort(ik[:, 0], kind="stable")]
    lo = np.searchsorted(ik[:, 0], ij[:, 0], side="left")
    hi = np.searchsorted(ik[:, 0], ij[:, 0], side="right")
    count = hi - lo
    first = np.repeat(np.arange(len(ij)), count)
    second = np.repeat(lo, count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    tri = np.column_stack([ij[first, 0], ij[first, 1], ik[second, 1]]).astype(np.int64)
    tri = tri[tri[:, 1] != tri[:, 2]]
    vec = pdb.vectors[tri]
    fits = np.abs(angle_between(vec[:, 1], vec[:, 2]) - a_jk) <= tolerance(a_jk)
    handed = np.sign(np.linalg.det(vec)) == np.sign(np.linalg.det(img_vec))
    return tri[fits & handed]


def match_pyramid(x: NDArray, y: NDArray, camera: Camera, pdb: PairDatabase, *, focal_tolerance: float = 0.0,
                  options: PyramidOptions | None = None) -> MatchOutcome:
    """Identify image stars with a known camera by triangles on the pair directory.

    Parameters
    ----------
    x, y : ndarray, shape (N,)
        Star positions (our pixel convention), brightest first.
    camera : Camera
        The camera (its focal length is taken as known to ``focal_tolerance``).
    pdb : PairDatabase
        A directory for (at least) this camera's diagonal field of view.
    focal_tolerance : float
        Relative uncertainty of the focal length (0.03 for a FOV known to 3 %); widens the angle
        tolerance and lets the confirmation refit the focal length.
    options : PyramidOptions, optional

    Returns
    -------
    MatchOutcome
        As :func:`.quad_matcher.match_lost_in_space`.
    """
    options = options or PyramidOptions()
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if len(x) < 4:
        return MatchOutcome(Status.TOO_FEW_STARS, f"the Pyramid needs at least 4 stars, got {len(x)}", None, 0)
    vec = camera.pixel_to_vector(x, y)
    noise = 3.0 * np.sqrt(2.0) * options.centroid_sigma_px / camera.fx

    def tolerance(angle):
        return noise + focal_tolerance * angle

    confirmer = Confirmer(x, y, match_radius_px(camera, options.match_radius_px), options.verify_stars,
                          options.max_false_match_prob, fit_focal=focal_tolerance > 0)
    stars = StarSet(pdb.tree, pdb.vectors, pdb.catalog_rows)
    deadline, trials = time.perf_counter() + options.timeout_s, 0
    for triad in pyramid_triads(min(len(x), options.stars)):
        img = np.array(triad)
        for tri in candidate_triangles(vec[img], pdb, tolerance):
            trials += 1
            rot = Rotation.from_quat(q_method_quaternions(vec[img][None], pdb.vectors[tri][None],
                                                          np.full((1, 3), 1 / 3))[0])
            found = confirmer.confirm(stars, rot, camera, img, trials)
            if found is not None:
                return MatchOutcome(Status.OK, "", found, trials)
            if time.perf_counter() > deadline:  # a triad of a dense field can have thousands
                break
        if time.perf_counter() > deadline:
            return MatchOutcome(Status.TIMEOUT, f"no match within the {options.timeout_s:g} s time limit", None, trials)
    return MatchOutcome(Status.NO_MATCH, f"no triangle of the {min(len(x), options.stars)} brightest stars matched "
                        f"the catalog ({trials} candidates tried)", None, trials)
