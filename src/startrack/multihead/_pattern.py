"""Identification on the combined star set of several heads when none can be identified alone.

Samaan 2002 Eq. 4–5 cites SP-Search (Mortari & Junkins 1999): star identification on the combined
vector set of several fields of view. A field with three stars has a triangle but nothing to
confirm it with: the lost-in-space matchers need a fourth star. Across a rig the other heads
confirm it:

1. For a head with at least three stars (most stars first), each triangle of its brightest stars
   (Mortari's Pyramid order, :func:`startrack.identify._star_order.ordered_star_sets`) is looked
   up in the star-pair directory of its field (:func:`startrack.identify._pyramid.candidate_triangles`:
   the three angles within ``3 sqrt(2)`` centroid sigmas, and the handedness).
2. Each candidate gives the head's attitude (q-method on three stars) and, through the mounting,
   the body's, with the covariance of a three-star fit.
3. The other heads' stars (and the pattern head's remaining stars), brightest first, are tested
   one at a time: each is matched to the nearest catalog star the current attitude predicts in
   its head, within a radius that follows the attitude's uncertainty carried into that head
   (:func:`.predict.predicted_sigma_px`; a triangle's roll is poor, and it is a cross-boresight
   shift for a head at 90 deg), and every match is added to a joint refit (:mod:`._joint`), which
   shrinks the radius for the next star.
4. If the attitude were wrong, star j would find a predicted star by chance with probability
   ``p_j = m pi r_j^2 / (W H)`` (m stars predicted in the W x H image of its head, r_j its radius;
   the heads see independent parts of the sky, and each p_j is conditional on the stars before
   it). k matches among n stars tested then have a chance probability of at most
   ``C(n, k) prod_j p_j``; times the candidates tried (Bonferroni) it must fall below
   ``max_false_match_prob`` (the reasoning of :mod:`startrack.identify._verify`, with radii that
   shrink as the evidence grows).

Two heads with three stars each are thus identified: a triangle in one, and three matches in the
other at radii of about 10, 3 and 3 px (1e-2 x 1e-3 x 1e-3 by chance, against 1e-6 at a fixed
10 px radius).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..attitude import covariance_batch, covariance_to_body, q_method_quaternions
from ..errors import require
from ..identify import (
    FieldStars,
    PairDatabase,
    PairSettings,
    candidate_triangles,
    load_pair_database,
    ordered_star_sets,
)
from ..results import Status
from ..track import EXTRA_PREDICTED, WindowMatcher
from ._joint import HeadMatch, fit_joint
from ._predict import MIN_PREDICTED, predicted_in_head, predicted_sigma_px
from ._solution import RigOptions
from ._stars import HeadStars


@dataclass(frozen=True)
class PatternOutcome:
    """The joint pattern's result: the body attitude and each head's matches, or a status."""

    status: Status
    reason: str
    rot_body_from_icrs: Rotation | None = None
    matches: dict[str, HeadMatch] | None = None
    false_match_prob: float = 1.0
    seed_head: str = ""


@dataclass(frozen=True)
class _Hypothesis:
    """A candidate: body attitude, its covariance (rad^2), the pattern's star rows and the catalog
    stars (indices into the field-star set of the matchers) they are taken for."""

    rot_body: Rotation
    cov_body: np.ndarray
    pattern: tuple[int, ...]
    catalog: tuple[int, ...]


def pair_database_for(stars: HeadStars) -> PairDatabase:
    """The star-pair directory for a head's field (diagonal, rounded up to a degree)."""
    return load_pair_database(PairSettings(fov_deg=float(math.ceil(stars.head.camera.fov_diagonal_deg))))


def joint_pattern(stars: dict[str, HeadStars], matchers: dict[str, WindowMatcher],
                  options: RigOptions) -> PatternOutcome:
    """Identify the rig from a triangle in one head confirmed by the others (module docstring)."""
    heads = sorted((s for s in stars.values() if len(s) >= 3), key=lambda s: -len(s))
    if not heads or sum(len(s) for s in stars.values()) < 5:
        return PatternOutcome(Status.TOO_FEW_STARS, "no head has a triangle of stars and another two to confirm "
                              f"it (stars per head: {_counts(stars)})")
    deadline, trials = time.perf_counter() + options.timeout_s, 0
    for pattern_head in heads:
        for hypothesis in _hypotheses(pattern_head, matchers[pattern_head.name].stars, options):
            trials += 1
            found = _confirmed(hypothesis, pattern_head, stars, matchers, options, trials)
            if found is not None:
                return found
            if time.perf_counter() > deadline:
                return PatternOutcome(Status.TIMEOUT, f"no joint pattern within {options.timeout_s:g} s "
                                      f"({trials} candidates tried)")
    return PatternOutcome(Status.NO_MATCH, f"no triangle of one head was confirmed by the others' stars "
                          f"({trials} candidates tried; stars per head: {_counts(stars)})")


def _counts(stars: dict[str, HeadStars]) -> str:
    return ", ".join(f"{name} {len(s)}" for name, s in stars.items())


def _hypotheses(pattern: HeadStars, catalog: FieldStars, options: RigOptions):
    """Body attitudes (with covariance) of every catalog triangle that fits a triangle of the head
    (its stars named by their index in ``catalog``, the matchers' star set)."""
    head, pdb = pattern.head, pair_database_for(pattern)
    sigma_rad = options.pattern_sigma_px / head.camera.fx
    noise = 3.0 * math.sqrt(2.0) * sigma_rad

    def tolerance(angle):
        return noise

    for triad in ordered_star_sets(3, min(len(pattern), options.pattern_stars)):
        img = list(triad)
        vec = pattern.vectors[img]
        cov_cam = covariance_batch(vec[None], np.full((1, 3), sigma_rad))[0]
        cov_body = covariance_to_body(cov_cam, head.rot_cam_from_body)
        for tri in candidate_triangles(vec, pdb, tolerance):
            index = catalog.index_of_row[pdb.catalog_rows[tri]]
            if np.any(index < 0):  # fainter than the predicted stars go
                continue
            quat = q_method_quaternions(vec[None], pdb.vectors[tri][None], np.full((1, 3), 1.0 / 3.0))[0]
            yield _Hypothesis(head.rot_cam_from_body.inv() * Rotation.from_quat(quat), cov_body, triad,
                              tuple(index.tolist()))


MAX_TESTED = 20
"""Stars of each head tested against a candidate (brightest first)."""


def _confirmed(hyp: _Hypothesis, pattern: HeadStars, stars: dict[str, HeadStars],
               matchers: dict[str, WindowMatcher], options: RigOptions, trials: int) -> PatternOutcome | None:
    """The outcome if the other heads' stars confirm the hypothesis, else None (module docstring)."""
    sigma = {n: s.head.centroid_sigma_px for n, s in stars.items()}
    # per head: matched star rows, catalog indices (of the matcher's set)
    pairs: dict[str, tuple[list[int], list[int]]] = {n: ([], []) for n in stars}
    pairs[pattern.name] = (list(hyp.pattern), list(hyp.catalog))
    rot, cov, log_p, tested = hyp.rot_body, hyp.cov_body, 0.0, 0
    for name in sorted(stars, key=lambda n: n == pattern.name):  # the pattern head's own stars last
        head_stars, matcher = stars[name], matchers[name]
        skip = hyp.pattern if name == pattern.name else ()
        for row in [i for i in range(len(head_stars)) if i not in skip][:MAX_TESTED]:
            tested += 1
            found = _nearest(head_stars, matcher, row, rot, cov, pairs[name][1], options.match_px)
            if found is None:
                continue
            index, p = found
            log_p += math.log(p)
            pairs[name][0].append(row)
            pairs[name][1].append(index)
            fit = require(fit_joint(list(_matches(stars, matchers, pairs).values()), sigma),
                          "the fit of three or more matched stars")
            rot, cov = fit.rot_body_from_icrs, fit.covariance_rad2
    confirming = sum(len(v[0]) for v in pairs.values()) - 3
    prob = min(1.0, trials * math.comb(tested, confirming) * math.exp(log_p)) if confirming else 1.0
    if confirming < 2 or prob > options.max_false_match_prob:
        return None
    return PatternOutcome(Status.OK, "", rot, _matches(stars, matchers, pairs), prob, pattern.name)


def _nearest(stars: HeadStars, matcher: WindowMatcher, row: int, rot: Rotation, cov: np.ndarray,
             taken: list[int], match_px: float) -> tuple[int, float] | None:
    """The nearest predicted catalog star (index into the matcher's set) to star ``row`` within the
    attitude's uncertainty radius, and the chance of finding one there (``m pi r^2 / (W H)``)."""
    head = stars.head
    radius = math.hypot(match_px, 3.0 * predicted_sigma_px(cov, head))
    count = max(MIN_PREDICTED, int(EXTRA_PREDICTED * len(stars)))
    idx, px, py = predicted_in_head(matcher, head, rot, radius, count)
    d2 = (px - stars.x[row]) ** 2 + (py - stars.y[row]) ** 2
    d2[np.isin(idx, taken)] = np.inf
    if idx.size == 0 or d2.min() > radius * radius:
        return None
    cam = head.camera
    return int(idx[int(np.argmin(d2))]), min(1.0, idx.size * math.pi * radius**2 / (cam.width * cam.height))


def _matches(stars: dict[str, HeadStars], matchers: dict[str, WindowMatcher],
             pairs: dict[str, tuple[list[int], list[int]]]) -> dict[str, HeadMatch]:
    """The matched pairs as :class:`.joint.HeadMatch` es."""
    out = {}
    for name, (rows, index) in pairs.items():
        catalog = matchers[name].stars
        picked = np.asarray(index, dtype=np.int64)
        out[name] = HeadMatch(stars[name], np.asarray(rows, dtype=np.int64), catalog.rows[picked],
                              catalog.vectors[picked])
    return out
