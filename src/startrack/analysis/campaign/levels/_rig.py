"""Level "rig": star lists of a rig of 1, 2 or 3 identical heads (:mod:`startrack.simulate._rig`),
solved jointly with :func:`startrack.solve_rig` (issue 18).

Head 0 looks along the body +z axis (its mounting is the identity, so the body frame is its camera
frame and the common columns' roll is its roll); head 1 is turned by ``separation_deg`` about the
body x axis, head 2 by ``separation_deg`` about the body y axis (at 90 deg the three boresights
are orthogonal). The trial's attitude is ``rot_body_from_icrs``. Every head gets its own star list
(centroid noise, drop-outs and false stars per head), with a Sun exclusion when ``sun_sep_deg`` is
given: the Sun is placed that far from head 0's boresight and blinds the heads whose
``sun_exclusion_deg`` cone it enters.

The common columns are the joint solution's (errors in the body = head 0 frame; ``sigma_*`` the
joint covariance about head 0's boresight). Extra columns: ``heads_used`` (heads whose stars are
in the joint fit), ``heads_blinded``, ``mode`` ("single-head", "joint-pattern" or ""),
``consistency_arcsec``, and head 0's own solution against the truth (``single_solved``,
``single_err_cross_arcsec``, ``single_err_roll_arcsec``), so one campaign compares the joint
solution with a single head's.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....camera import Camera
from ....multihead import BrightBodies, RigOptions, solve_rig
from ....rig import CameraRig, Exclusion, RigHead
from ....simulate import rig_star_lists
from ....units import ARCSEC
from .._outcome import NAN, error_columns, truth_columns
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS, SOLVER_PARAMS

RIG_PARAMS = (
    Param("heads", "int", 2, "camera heads: 1, 2 or 3 (head 0 along body +z, 1 about body x, 2 about body y)",
          lo=1, hi=3),
    Param("separation_deg", "float", 90.0, "angle between head 0's boresight and each other head's (deg)",
          lo=0.0, hi=180.0),
    Param("max_mag", "float", 6.0, "faintest catalog star in the lists (V)", lo=-2.0, hi=12.0),
    Param("centroid_sigma_px", "float", 0.2, "centroid noise of every head, 1-sigma per axis (px)", lo=0.0, hi=100.0),
    Param("drop_fraction", "float", 0.0, "fraction of each head's real stars left out", lo=0.0, hi=0.99),
    Param("false_stars", "int", 0, "false stars added to each head's list", lo=0, hi=10000),
    Param("max_stars", "int", 40, "each head's list is cut to its brightest entries", lo=1, hi=100000),
    Param("sun_sep_deg", "float", None, 'angle from head 0\'s boresight to the Sun (deg); "auto": no Sun',
          lo=0.0, hi=180.0, optional=True),
    Param("sun_exclusion_deg", "float", 30.0, "Sun exclusion half-angle of every head (deg)", lo=0.0, hi=180.0),
)
PARAMS = params_by_name(CAMERA_PARAMS, RIG_PARAMS, tuple(p for p in SOLVER_PARAMS if p.name in ("method",
                                                                                                  "epoch_jyear")))
COLUMNS = {"heads_used": pa.int32(), "heads_blinded": pa.int32(), "mode": pa.string(),
           "consistency_arcsec": pa.float64(), "single_solved": pa.bool_(),
           "single_err_cross_arcsec": pa.float64(), "single_err_roll_arcsec": pa.float64()}


def check(params: Mapping[str, Any]) -> None:
    """Refuse a rig whose heads coincide."""
    if params["heads"] > 1 and params["separation_deg"] == 0.0:
        raise SpecError("separation_deg: heads 1 and 2 would look where head 0 does; give an angle > 0")


@functools.lru_cache(maxsize=32)
def rig_of(heads: int, separation_deg: float, fov_deg: float, width: int, height: int,
           sun_exclusion_deg: float) -> CameraRig:
    """The level's rig (module docstring)."""
    camera = Camera.from_fov(width, height, fov_deg)
    exclusion = Exclusion(sun_deg=sun_exclusion_deg, earth_limb_deg=0.0, moon_deg=0.0)
    mounts = [Rotation.identity(), Rotation.from_euler("x", separation_deg, degrees=True),
              Rotation.from_euler("y", separation_deg, degrees=True)]
    return CameraRig([RigHead(f"h{k}", camera, mounts[k], exclusion=exclusion) for k in range(heads)])


def sun_bodies(rot_body: Rotation, sun_sep_deg: float | None, rng: np.random.Generator) -> BrightBodies | None:
    """The Sun ``sun_sep_deg`` from head 0's boresight (at a random position angle); Earth and Moon
    far behind (their exclusion angles are 0 in this level)."""
    if sun_sep_deg is None:
        return None
    angle = rng.uniform(0.0, 2.0 * math.pi)
    axis = rot_body.inv().apply([math.cos(angle), math.sin(angle), 0.0])  # across head 0's boresight, ICRS
    sun = Rotation.from_rotvec(axis * math.radians(sun_sep_deg)).apply(rot_body.inv().apply([0.0, 0.0, 1.0]))
    return BrightBodies(sun_icrs=sun, earth_icrs=-sun, moon_icrs=-sun, sun_radius_rad=math.radians(0.27),
                        earth_radius_rad=0.0, moon_radius_rad=0.0)


def _single(solution, rot: Rotation) -> dict[str, Any]:
    own = solution.heads.get("h0")
    if own is None or not own.solved:
        return {"single_solved": False, "single_err_cross_arcsec": NAN, "single_err_roll_arcsec": NAN}
    ex, ey, ez = (rot * own.rot_cam_from_icrs.inv()).as_rotvec()  # head 0's frame is the body frame
    return {"single_solved": True, "single_err_cross_arcsec": math.hypot(ex, ey) / ARCSEC,
            "single_err_roll_arcsec": ez / ARCSEC}


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One rig frame of star lists at body attitude ``rot``, solved jointly."""
    rig = rig_of(params["heads"], params["separation_deg"], params["fov_deg"], params["width"], params["height"],
                 params["sun_exclusion_deg"])
    bodies = sun_bodies(rot, params["sun_sep_deg"], rng)
    lists = rig_star_lists(rig, rot, max_mag=params["max_mag"], epoch_jyear=params["epoch_jyear"], rng=rng,
                           sigma_px=params["centroid_sigma_px"], max_stars=params["max_stars"],
                           drop_fraction=params["drop_fraction"], false_stars=params["false_stars"], bodies=bodies)
    sol = solve_rig({n: s.stars for n, s in lists.items()}, rig, epoch=params["epoch_jyear"],
                    method=params["method"], options=RigOptions())
    camera = rig.head("h0").camera
    row = {"status": sol.status.name, "error": "", "solved": sol.solved,
           "sigma_cross_arcsec": sol.sigma_cross_arcsec.get("h0", NAN) if sol.solved else NAN,
           "sigma_roll_arcsec": sol.sigma_roll_arcsec.get("h0", NAN) if sol.solved else NAN,
           "n_stars": int(sum(len(s) for s in lists.values())), "n_matched": sol.n_matched if sol.solved else 0,
           "false_match_prob": float(sol.false_match_prob), "time_s": float(sol.solve_time_s),
           **error_columns(rot, sol.rot_body_from_icrs if sol.solved else None, camera, tolerance_px),
           **truth_columns(rot),
           "heads_used": len(sol.heads_used), "heads_blinded": sum(bool(s.blinded_by) for s in lists.values()),
           "mode": sol.mode, "consistency_arcsec": sol.consistency_deg * 3600.0 if sol.solved else NAN,
           **_single(sol, rot)}
    return TrialOutput(row, truth=lists)


LEVEL = register(Level(
    name="rig", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns=COLUMNS, chunk_trials=50))
