"""``solve_rig``: one body attitude from the stars of every head of a rig, star by star.

1. **Seed.** The head with the most stars is identified lost-in-space
   (:func:`startrack.solve_stars` with its camera); if it fails, the next one. When no head can be
   identified alone, the joint pattern across heads (:mod:`._pattern`) seeds the rig.
2. **Predict and match.** From the body attitude every head's stars are predicted through its
   mounting and matched in windows as in tracking mode (:mod:`._predict`); the windows start as wide
   as the seed's uncertainty carried into the head (a single head's roll) and shrink to
   :attr:`RigOptions.match_px` once the joint attitude is fitted.
3. **Joint fit.** One Wahba solution over all matched stars of all heads in the body frame, each
   weighted by its head's measured centroid noise (:mod:`._joint`), repeated with the new matches
   and noise estimates.
4. **Consistency.** A head whose stars the prediction did not find, or found less than half of
   (a wrong mounting moves them out of the windows), is identified on its own if it can be. Every
   head with its own solution is compared, through its mounting, with an *anchor* (the head that
   the most other heads agree with; among equals the rig's reference head, then the head with the
   most matched stars): a
   chi-square above :attr:`RigOptions.consistency_chi2` marks the head inconsistent; it is left
   out and the rig is solved again from the anchor. ``consistency_deg`` is the largest angle
   between a head's own solution and the joint one.

Stars of a split detector that could belong to either field are in both heads' lists
(:mod:`._split_fov`); when both match such a spot, the field whose prediction lies closer keeps it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, get_args

import numpy as np
from scipy.spatial.transform import Rotation

from ..catalog import load_catalog
from ..errors import check_choice, check_instance, require
from ..frames import angle_between
from ..identify import MethodName, field_stars
from ..results import AttitudeSolution, StarMatches, Status
from ..rig import CameraRig
from ..solve import epoch_jyear, solve_stars
from ..track import WindowMatcher
from ..units import ARCSEC
from ._joint import (
    HeadMatch,
    JointFit,
    chi2_against_joint,
    disagreement,
    fit_joint,
    head_split_arcsec,
    measured_sigma_px,
    own_body,
    own_solution,
    residuals_px,
)
from ._pattern import joint_pattern
from ._predict import head_matcher, match_predicted, predicted_sigma_px
from ._solution import IDENTIFIED_BY_HEAD, IDENTIFIED_JOINTLY, RigOptions, RigSolution
from ._stars import HeadStars, rig_stars

if TYPE_CHECKING:
    from astropy.time import Time

LIS_MIN_STARS = 4
"""A head is identified lost-in-space on its own only with this many stars (a pattern and one more)."""

UNMATCHED_CHECK = 0.5
"""A head whose windows matched less than this share of its stars is also identified on its own."""


@dataclass(frozen=True)
class _Seed:
    """A first body attitude, its covariance (body frame, rad^2), where it came from."""

    rot_body: Rotation
    cov_body: np.ndarray
    head: str
    mode: str
    false_match_prob: float


@dataclass
class _Work:
    """What one solve knows so far (mutable while it runs)."""

    stars: dict[str, HeadStars]
    matchers: dict[str, WindowMatcher]
    options: RigOptions
    epoch: float
    method: MethodName
    lis: dict[str, AttitudeSolution]


def solve_rig(stars: Mapping[str, tuple], rig: CameraRig, *, epoch: Time | float | None = None,
              method: MethodName = "quads",
              options: RigOptions | None = None) -> RigSolution:
    """One attitude from the stars of every head of a rig (module docstring).

    Parameters
    ----------
    stars : mapping of str to tuple of arrays
        Head name to its stars: ``(x, y)`` or ``(x, y, flux)``, arrays of shape (N,) in our pixel
        convention (0-based pixel centres, x = column), brightest first unless ``flux`` is given.
        Heads left out have no stars.
    rig : CameraRig
    epoch : astropy.time.Time or float, optional
        Catalog epoch (Julian year, TDB); default J2000.0.
    method : str
        Lost-in-space matcher for a single head: one of :data:`RIG_METHODS` (every
        :data:`startrack.identify.MethodName` but "overlay", which needs a prior attitude).
    options : RigOptions, optional

    Returns
    -------
    RigSolution
        OK with ``rot_body_from_icrs``, the body-frame covariance, each head's own solution and
        matches, and ``consistency_deg``; TOO_FEW_STARS / NO_MATCH / TIMEOUT with a reason.

    Raises
    ------
    InvalidInputError
        A star list for a head that is not in the rig, a malformed list (naming the head), an
        unknown ``method``.
    """
    options = RigOptions() if options is None else check_instance(options, RigOptions, "options")
    return solve_head_stars(rig_stars(stars, rig), rig, epoch_jyear(epoch), check_method(method), options)


RIG_METHODS: tuple[MethodName, ...] = tuple(m for m in get_args(MethodName) if m != "overlay")
"""The matchers a rig can run on one head lost-in-space: all but "overlay", which needs a prior."""


def check_method(method: str) -> MethodName:
    """``method`` as one of :data:`RIG_METHODS`; an InvalidInputError naming it and the valid ones."""
    return check_choice(method, RIG_METHODS, "method")


def solve_head_stars(stars: dict[str, HeadStars], rig: CameraRig, epoch: float, method: MethodName,
                     options: RigOptions) -> RigSolution:
    """:func:`solve_rig` on checked star lists (:func:`.stars.rig_stars`)."""
    t0 = time.perf_counter()
    catalog = field_stars(options.catalog_max_mag, epoch)
    work = _Work(stars, {n: head_matcher(s.head, catalog) for n, s in stars.items()}, options, epoch, method, {})
    seed = _seed_by_head(work)
    if seed is None:
        seed, failure = _seed_jointly(work)
        if seed is None:
            return replace(require(failure, "the failed joint solve"), heads=dict(work.lis),
                           solve_time_s=time.perf_counter() - t0)
    solution = _settled(work, rig, seed)
    return replace(solution, solve_time_s=time.perf_counter() - t0)


# --- seeds ------------------------------------------------------------------------------------
def _lost_in_space(work: _Work, stars: HeadStars) -> AttitudeSolution:
    """The head identified on its own (once per solve); ``det_index`` as the caller numbers stars."""
    if stars.name not in work.lis:
        head = stars.head
        if len(stars) < LIS_MIN_STARS:
            sol = AttitudeSolution(status=Status.TOO_FEW_STARS, reason=f"head {head.name!r}: {len(stars)} star(s); "
                                   f"lost-in-space on one head needs {LIS_MIN_STARS}")
        else:
            sol = solve_stars(stars.x, stars.y, camera=head.camera, epoch=work.epoch,
                              method=work.method)
            if sol.solved:
                sol = replace(sol, matches=replace(sol.matches, det_index=stars.index[sol.matches.det_index]))
            else:
                sol = replace(sol, reason=f"head {head.name!r}: {sol.reason}")
        work.lis[stars.name] = sol
    return work.lis[stars.name]


def _seed_by_head(work: _Work) -> _Seed | None:
    """The first head (most stars first) identified lost-in-space, as a body attitude."""
    for stars in sorted(work.stars.values(), key=lambda s: -len(s)):
        if len(stars) < LIS_MIN_STARS:
            break
        sol = _lost_in_space(work, stars)
        if sol.solved:
            rot, cov = own_body(sol, stars.head)
            return _Seed(rot, cov, stars.name, IDENTIFIED_BY_HEAD, sol.false_match_prob)
    return None


def _seed_jointly(work: _Work) -> tuple[_Seed | None, RigSolution | None]:
    """The joint pattern's attitude, fitted to its matches; or the failed RigSolution."""
    found = joint_pattern(work.stars, work.matchers, work.options)
    if found.status is Status.OK:
        sigma = {n: s.head.centroid_sigma_px for n, s in work.stars.items()}
        fit = fit_joint(list(require(found.matches, "the joint pattern's matches").values()), sigma)
        if fit is not None:
            return _Seed(fit.rot_body_from_icrs, fit.covariance_rad2, found.seed_head, IDENTIFIED_JOINTLY,
                         found.false_match_prob), None
    single = "; ".join(s.reason for s in work.lis.values() if s.reason)
    reason = found.reason if not single else f"{found.reason}; alone: {single}"
    return None, RigSolution(status=found.status, reason=reason)


# --- predict, match, fit ----------------------------------------------------------------------
def _refined(work: _Work, rot: Rotation, cov: np.ndarray, used: list[str]
             ) -> tuple[dict[str, HeadMatch], JointFit | None, dict[str, float]]:
    """Predict-match-fit rounds from a body attitude over the heads ``used``."""
    opt = work.options
    sigma = {n: work.stars[n].head.centroid_sigma_px for n in used}
    radius = {n: max(opt.window_px, opt.window_sigmas * predicted_sigma_px(cov, work.stars[n].head)) for n in used}
    matches: dict[str, HeadMatch] = {}
    fit: JointFit | None = None
    for round_ in range(opt.refine_rounds):
        before = matches
        matches = {n: match_predicted(work.stars[n], work.matchers[n], rot, radius[n])[0] for n in used}
        matches = _without_shared(matches, rot)
        if round_ > 0 and _same(before, matches):
            break
        fit = fit_joint(list(matches.values()), sigma)
        if fit is None:
            return matches, None, sigma
        rot, cov = fit.rot_body_from_icrs, fit.covariance_rad2
        for n in used:
            head = work.stars[n].head
            sigma[n] = measured_sigma_px(matches[n], head.rot_cam_from_icrs(rot), opt.min_sigma_px)
            radius[n] = math.hypot(opt.match_px, 3.0 * predicted_sigma_px(cov, head))
    return matches, fit_joint(list(matches.values()), sigma), sigma


def _same(a: dict[str, HeadMatch], b: dict[str, HeadMatch]) -> bool:
    """Whether two rounds matched the same stars to the same catalog stars."""
    return a.keys() == b.keys() and all(np.array_equal(a[n].image_index, b[n].image_index)
                                        and np.array_equal(a[n].catalog_rows, b[n].catalog_rows) for n in a)


def _without_shared(matches: dict[str, HeadMatch], rot: Rotation) -> dict[str, HeadMatch]:
    """A spot of a split detector matched in both of its fields stays with the closer prediction."""
    by_detector: dict[str, list[str]] = {}
    for name, m in matches.items():
        by_detector.setdefault(m.stars.head.detector_name, []).append(name)
    out = dict(matches)
    for names in (v for v in by_detector.values() if len(v) > 1):
        best: dict[int, tuple[float, str]] = {}
        for name in names:
            m = matches[name]
            d2 = np.sum(residuals_px(m, m.stars.head.rot_cam_from_icrs(rot)) ** 2, axis=1)
            for ident, dist in zip(m.stars.index[m.image_index].tolist(), d2.tolist(), strict=True):
                if ident not in best or dist < best[ident][0]:
                    best[ident] = (dist, name)
        for name in names:
            m = matches[name]
            keep = np.array([best[i][1] == name for i in m.stars.index[m.image_index].tolist()], dtype=bool)
            out[name] = m.take(keep)
    return out


# --- own solutions and consistency ------------------------------------------------------------
def _own_solutions(work: _Work, matches: dict[str, HeadMatch], false_match_prob: float) -> dict[str, AttitudeSolution]:
    """Each head's own solution: from its matched stars; from lost-in-space on it alone when the
    windows matched less than half of its stars (a mounting off by about a window matches only
    the stars the error moves least, whose own fit cannot show the error) and that matches more."""
    own = {}
    for name, stars in work.stars.items():
        match = matches.get(name, HeadMatch.empty(stars))
        sol = own_solution(match, work.options.min_sigma_px, work.options.min_head_stars, false_match_prob)
        if len(match) < UNMATCHED_CHECK * len(stars):
            alone = _lost_in_space(work, stars)
            if alone.solved and len(alone.matches) > len(match):
                sol = alone
        own[name] = sol
    return own


def _anchor(rig: CameraRig, own: dict[str, AttitudeSolution], chi2_max: float) -> str | None:
    """The head with its own solution that the most other heads agree with (by chi-square), the
    reference head first among equals, then the head with the most matched stars: a head given
    another head's stars, or a wrong mounting, is outvoted when two others agree."""
    solved = [n for n, s in own.items() if s.solved]
    if not solved:
        return None

    def standing(name: str) -> tuple[int, bool, int]:
        agree = len(solved) - 1 - len(_disagreeing(rig, own, name, chi2_max))
        return agree, name == rig.reference, len(own[name].matches)

    return max(solved, key=standing)


def _disagreeing(rig: CameraRig, own: dict[str, AttitudeSolution], anchor: str, chi2_max: float) -> set[str]:
    """Heads whose own attitude (through the mounting) the anchor's refuses by chi-square."""
    rot_a, cov_a = own_body(own[anchor], rig.head(anchor))
    out = set()
    for name, sol in own.items():
        if name != anchor and sol.solved:
            rot, cov = own_body(sol, rig.head(name))
            if disagreement(rot, cov, rot_a, cov_a)[1] > chi2_max:
                out.add(name)
    return out


def _settled(work: _Work, rig: CameraRig, seed: _Seed) -> RigSolution:
    """Steps 2-4 of the module docstring from a seed."""
    excluded: set[str] = set()
    rot, cov = seed.rot_body, seed.cov_body
    for _ in range(len(rig)):
        matches, fit, sigma = _refined(work, rot, cov, [n for n in work.stars if n not in excluded])
        own = _own_solutions(work, matches, seed.false_match_prob)
        anchor = _anchor(rig, own, work.options.consistency_chi2)
        if anchor is None:
            break
        new = _disagreeing(rig, own, anchor, work.options.consistency_chi2) - excluded
        if not new:
            break
        excluded |= new
        rot, cov = own_body(own[anchor], rig.head(anchor))
    else:  # the last round excluded a head: fit once more without it
        matches, fit, sigma = _refined(work, rot, cov, [n for n in work.stars if n not in excluded])
        own = _own_solutions(work, matches, seed.false_match_prob)
    if fit is None:
        return RigSolution(status=Status.NO_MATCH, reason="the matched stars of the heads do not fix an attitude",
                           heads=own)
    return _solution(work, rig, seed, matches, fit, sigma, own, tuple(sorted(excluded)))


def _solution(work: _Work, rig: CameraRig, seed: _Seed, matches: dict[str, HeadMatch], fit: JointFit,
              sigma: dict[str, float], own: dict[str, AttitudeSolution], excluded: tuple[str, ...]) -> RigSolution:
    rot = fit.rot_body_from_icrs
    used = tuple(n for n in work.stars if n in matches and len(matches[n]))
    split = {n: head_split_arcsec(fit.covariance_rad2, rig.head(n)) for n in work.stars}
    return RigSolution(
        status=Status.OK, rot_body_from_icrs=rot, covariance_rad2=fit.covariance_rad2, heads=own,
        matches={n: _star_matches(matches.get(n), seed.false_match_prob) for n in work.stars},
        consistency_deg=_consistency_deg(rig, own, fit), heads_used=used, inconsistent_heads=excluded,
        sigma_cross_arcsec={n: v[0] for n, v in split.items()}, sigma_roll_arcsec={n: v[1] for n, v in split.items()},
        centroid_sigma_px={n: sigma.get(n, work.stars[n].head.centroid_sigma_px) for n in work.stars},
        residuals_arcsec={n: _residuals_arcsec(matches[n], rot) for n in used},
        mode=seed.mode, seed_head=seed.head, false_match_prob=seed.false_match_prob)


def _star_matches(match: HeadMatch | None, false_match_prob: float) -> StarMatches:
    if match is None or len(match) == 0:
        return StarMatches(status=Status.NO_MATCH, reason="no star of this head matched")
    return StarMatches(status=Status.OK, det_index=match.stars.index[match.image_index],
                       hip=load_catalog().hip[match.catalog_rows].astype(np.int64), cat_vectors=match.ref_icrs,
                       false_match_prob=false_match_prob)


def _residuals_arcsec(match: HeadMatch, rot_body: Rotation) -> np.ndarray:
    return angle_between(rot_body.apply(match.ref_icrs).reshape(-1, 3), match.observed_body) / ARCSEC


def _consistency_deg(rig: CameraRig, own: dict[str, AttitudeSolution], fit: JointFit) -> float:
    """Largest angle (deg) between a head's own attitude, through its mounting, and the joint one."""
    angles = [disagreement(*own_body(s, rig.head(n)), fit.rot_body_from_icrs, fit.covariance_rad2)[0]
              for n, s in own.items() if s.solved]
    return math.degrees(max(angles)) if angles else float("nan")


def consistency_chi2(solution: RigSolution, rig: CameraRig, name: str) -> float:
    """Chi-square of head ``name``'s own attitude against the joint one (NaN without its own solution)."""
    own = solution.heads.get(name)
    if own is None or not own.solved or not solution.solved:
        return float("nan")
    rot, cov = own_body(own, rig.head(name))
    joint = JointFit(solution.rot_body_from_icrs, require(solution.covariance_rad2, "the rig solution's covariance"))
    return chi2_against_joint(rot, cov, joint, name in solution.heads_used)


__all__ = ["RIG_METHODS", "check_method", "consistency_chi2", "solve_head_stars", "solve_rig"]
