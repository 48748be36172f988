"""Level "stars": catalog stars projected with centroid noise, drop-outs, false stars and
magnitude noise (:mod:`startrack.analysis._starlists`, the lists of ``benchmarks/lis_benchmark.py``),
then :func:`startrack.solve_stars`.

Each trial makes one list at its attitude from its own generator; ``max_mag = "auto"`` takes the
limit at which a field of the camera holds ``target_stars`` catalog stars on average.
Extra columns: ``max_mag_used`` (V) and ``n_false`` (false stars in the list handed over).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....solve import solve_stars
from ..._starlists import Conditions, Sky, load_sky, make_star_list
from .._outcome import solution_columns
from .._params import Param, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS, SOLVER_PARAMS, check_solver, solver_kwargs

STAR_LIST_PARAMS = (
    Param("max_mag", "float", 6.0, 'faintest catalog star (V); "auto": a field holds target_stars on average',
          lo=-2.0, hi=12.0, optional=True),
    Param("target_stars", "float", 25.0, 'mean catalog stars per field that max_mag = "auto" aims for',
          lo=1.0, hi=10000.0),
    Param("centroid_sigma_px", "float", 0.2, "centroid noise, 1-sigma per axis (px)", lo=0.0, hi=100.0),
    Param("drop_fraction", "float", 0.0, "fraction of the real stars left out (missed detections)",
          lo=0.0, hi=0.99),
    Param("false_stars", "int", 0, "false stars added at uniformly random positions", lo=0, hi=10000),
    Param("false_star_mag_span", "float", 3.0, "false stars are uniform in [max_mag - span, max_mag] (mag)",
          lo=0.0, hi=20.0),
    Param("mag_sigma", "float", 0.1, "magnitude noise, 1-sigma (mag); reorders the list", lo=0.0, hi=5.0),
    Param("max_stars", "int", 40, "the list is cut to its brightest entries", lo=3, hi=100000),
)

PARAMS = params_by_name(CAMERA_PARAMS, STAR_LIST_PARAMS, SOLVER_PARAMS)


def conditions(params: Mapping[str, Any]) -> Conditions:
    """The star-list conditions of a trial (every range collapsed to the cell's value)."""
    return Conditions(
        fov_deg=params["fov_deg"], width=params["width"], height=params["height"],
        sigma_px_range=(params["centroid_sigma_px"],) * 2,
        missing_fraction_range=(params["drop_fraction"],) * 2,
        false_stars_range=(params["false_stars"],) * 2, mag_noise=params["mag_sigma"],
        false_star_mag_span=params["false_star_mag_span"], target_stars=params["target_stars"],
        max_stars=params["max_stars"], max_mag=params["max_mag"], epoch_jyear=params["epoch_jyear"])


@functools.lru_cache(maxsize=16)
def _sky(cond: Conditions) -> Sky:
    return load_sky(cond)


def sky_for(cond: Conditions) -> Sky:
    """The catalog stars of these conditions, kept per process (only what sets the limit and the
    epoch is in the key)."""
    key = Conditions(fov_deg=cond.fov_deg, width=cond.width, height=cond.height, target_stars=cond.target_stars,
                     max_mag=cond.max_mag, epoch_jyear=cond.epoch_jyear)
    if cond.max_mag is not None:  # the limit is given: the camera does not matter
        key = Conditions(max_mag=cond.max_mag, epoch_jyear=cond.epoch_jyear)
    return _sky(key)


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One star list at ``rot`` (``rot_cam_from_icrs``), solved lost-in-space."""
    cond = conditions(params)
    sky = sky_for(cond)
    stars = make_star_list(sky, cond, rng, rot)
    solution = solve_stars(stars.x, stars.y, width=cond.width, height=cond.height, flux=stars.flux,
                           **solver_kwargs(params))
    row = solution_columns(solution, rot, cond.camera, tolerance_px, len(stars))
    row.update(max_mag_used=float(sky.max_mag), n_false=int(np.count_nonzero(~stars.is_real)))
    return TrialOutput(row, truth=stars)


LEVEL = register(Level(
    name="stars", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check_solver,
    columns={"max_mag_used": pa.float64(), "n_false": pa.int32()}, chunk_trials=250))
