"""Level "groupmatch": Jacobs 1995's lost-in-space matching trade, one star list in the Sunsat
attitude region matched by one method (Jacobs 1995 §3.5, Tables 3-5 to 3-7).

The trial's attitude is drawn from the seed's orbit region, not from the campaign's attitudes;
the list is every V <= 6 star in the Sunsat field with the row's position and magnitude noise
(:mod:`._sunsat`). ``seed_row`` (1-5) sets the row's sigma_p, sigma_Mv, d_uncert and Mv_uncert;
each of the four may be set instead ("auto": the row's). Methods (``match_method``):

- ``vb-sub``: :func:`startrack.identify._match_groups.match_van_bezooijen` with magnitudes on the
  region's sub-catalogue (the seed's), confirmed (false-match bound 1e-6), its attitude refitted
  on its matches;
- ``vb-group``: the seed's own criterion: the first group that steps 1-5 recognise among the 8
  brightest stars is the identification (no confirmation, no attitude);
- ``vb-allsky``: ``vb-sub`` on every V <= 6 star (about ten times the seed's catalogue);
- ``quads``: the default solver, ``solve_stars(x, y, camera=sunsat)`` (no tolerances).

A returned identification is **wrong** when a star is given a star more than a pixel angle from
its own (the fainter component of an unresolved double does not count) or the boresight is off
by more than ``wrong_px`` pixel angles (roll is not judged: with a few stars 0.4 px of noise can
turn it by 5 pixel angles). Common columns: ``status`` the matcher's; ``solved`` an
identification was returned; ``correct`` = solved and not wrong (the seed's "success"; not the
roll-weighted tolerance of the other levels); the error columns from the attitude (NaN for
``vb-group``); ``n_stars`` the list's length; ``time_s`` the matcher's time; the true attitude.
Extra columns: ``wrong``, ``fail_few`` (unsolved with fewer than 3 stars: the seed's "fail, < 3
stars"), ``fail_many`` (unsolved with 3 or more).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....catalog import load_catalog
from ....frames import angle_between, boresight
from ....identify import GroupProblem, VanBezooijenOptions, candidate_groups, match_pairs, refine_pointing
from ....identify import match_van_bezooijen as vb_match
from ....solve import solve_stars
from .._outcome import NAN, error_columns, truth_columns
from .._params import Param, params_by_name
from . import Level, TrialOutput, register
from ._sunsat import CAMERA, SEED_ROWS, Guides, StarList, guides, misidentified, region_attitudes, star_list

METHODS = ("vb-sub", "vb-group", "vb-allsky", "quads")
ROW_KEYS = tuple(SEED_ROWS[1])

PARAMS = params_by_name((
    Param("seed_row", "int", 2, "the row of Jacobs 1995's Tables 3-5 to 3-7 (noise and tolerances)", lo=1, hi=5),
    Param("sigma_p_urad", "float", None, "star position noise per axis (urad); auto: the row's", lo=0.0, hi=1e5,
          optional=True),
    Param("sigma_mv", "float", None, "magnitude noise (mag); auto: the row's", lo=0.0, hi=10.0, optional=True),
    Param("d_uncert_urad", "float", None, "distance tolerance of the match (urad); auto: the row's", lo=0.1,
          hi=1e5, optional=True),
    Param("mv_uncert", "float", None, "magnitude tolerance of the match (mag); auto: the row's", lo=0.0, hi=10.0,
          optional=True),
    Param("match_method", "str", "vb-sub", "vb-sub, vb-group, vb-allsky or quads (module docstring)",
          choices=METHODS),
    Param("timeout_s", "float", 5.0, "van Bezooijen's time limit per list (s)", lo=0.01, hi=3600.0),
    Param("wrong_px", "float", 5.0, "a boresight off by more than this many pixel angles is wrong", lo=0.1,
          hi=1000.0),
))


def row_values(params: Mapping[str, Any]) -> dict[str, float]:
    """sigma_p_urad, sigma_mv, d_uncert_urad, mv_uncert: the seed row's, or the values set."""
    row = SEED_ROWS[params["seed_row"]]
    return {key: row[key] if params[key] is None else params[key] for key in ROW_KEYS}


@dataclass(frozen=True)
class Outcome:
    """What a method returned for one list: its status, the HIP numbers it gave the stars and their
    true ones (empty when unsolved), the attitude (None for ``vb-group``), the false-match bound
    (NaN for ``vb-group``, 1 when unsolved) and the time (s)."""

    status: str
    given_hip: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    true_hip: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    rot_cam_from_icrs: Rotation | None = None
    false_match_prob: float = 1.0
    time_s: float = 0.0

    @property
    def solved(self) -> bool:
        return self.status == "OK"


def _vb(s: StarList, pdb, values: dict, timeout_s: float) -> Outcome:
    """The confirmed van Bezooijen match, its attitude refitted on its matches."""
    options = VanBezooijenOptions(distance_tolerance_rad=values["d_uncert_urad"] * 1e-6,
                                  mag_tolerance=values["mv_uncert"], timeout_s=timeout_s,
                                  centroid_sigma_px=values["sigma_p_urad"] * 1e-6 * CAMERA.fx)
    res = vb_match(s.x, s.y, CAMERA, pdb, options=options, magnitudes=s.mags)
    cand = res.candidate
    if cand is None:
        return Outcome(res.status.name)
    ref = load_catalog().take(cand.catalog_rows).vectors(2000.0)
    rot = refine_pointing(cand.rot_cam_from_icrs, CAMERA, ref, s.x[cand.image_index], s.y[cand.image_index],
                          fit_focal=False)[0]
    return Outcome("OK", load_catalog().hip[cand.catalog_rows], s.hip[cand.image_index], rot, cand.false_match_prob)


def _group(s: StarList, g: Guides, values: dict, timeout_s: float) -> Outcome:
    """The seed's criterion: the first recognised group of the 8 brightest, unconfirmed."""
    n = min(8, len(s))
    if n < 3:
        return Outcome("TOO_FEW_STARS")
    d_uncert = values["d_uncert_urad"] * 1e-6
    problem = GroupProblem(CAMERA.pixel_to_vector(s.x[:n], s.y[:n]), g.sub.vectors, lambda angle: d_uncert)
    rows = match_pairs(problem, g.sub, s.mags[:n], load_catalog().v_mag[g.sub.catalog_rows], values["mv_uncert"])
    group = next(candidate_groups(problem, rows, time.perf_counter() + timeout_s), (None, 0))[0]
    if group is None:
        return Outcome("NO_MATCH")
    o, k = problem.split(group)
    return Outcome("OK", load_catalog().hip[g.sub.catalog_rows[k]], s.hip[o], false_match_prob=NAN)


def _quads(s: StarList) -> Outcome:
    sol = solve_stars(s.x, s.y, camera=CAMERA, method="quads")
    if not sol.solved:
        return Outcome(sol.status.name)
    return Outcome("OK", sol.matches.hip, s.hip[sol.matches.det_index], sol.rot_cam_from_icrs, sol.false_match_prob)


def match(params: Mapping[str, Any], s: StarList, g: Guides) -> Outcome:
    """Run the cell's method on one list, timed."""
    method, values = params["match_method"], row_values(params)
    t0 = time.perf_counter()
    if method == "quads":
        out = _quads(s)
    elif method == "vb-group":
        out = _group(s, g, values, params["timeout_s"])
    else:
        out = _vb(s, g.sub if method == "vb-sub" else g.full, values, params["timeout_s"])
    return replace(out, time_s=time.perf_counter() - t0)


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One list in the region, matched (``rot``, the campaign's attitude, is not used)."""
    g = guides()
    truth = region_attitudes(1, rng)[0]
    values = row_values(params)
    s = star_list(truth, g, values["sigma_p_urad"] * 1e-6, values["sigma_mv"], rng)
    out = match(params, s, g)
    est = out.rot_cam_from_icrs
    off = float(angle_between(boresight(truth), boresight(est))) if est is not None else 0.0
    wrong = out.solved and (misidentified(out.given_hip, out.true_hip) or off > params["wrong_px"] / CAMERA.fx)
    row = {"status": out.status, "error": "", "solved": out.solved, "sigma_cross_arcsec": NAN,
           "sigma_roll_arcsec": NAN, "n_stars": len(s), "n_matched": int(out.given_hip.size),
           "false_match_prob": float(out.false_match_prob), "time_s": out.time_s,
           **error_columns(truth, est, CAMERA, tolerance_px), **truth_columns(truth)}
    row.update(correct=out.solved and not wrong, wrong=bool(wrong), fail_few=not out.solved and len(s) < 3,
               fail_many=not out.solved and len(s) >= 3)
    return TrialOutput(row, truth=s)


LEVEL = register(Level(
    name="groupmatch", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run,
    columns={"wrong": pa.bool_(), "fail_few": pa.bool_(), "fail_many": pa.bool_()}, chunk_trials=10))
