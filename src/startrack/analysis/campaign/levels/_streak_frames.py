"""Level "streak_frames": an ordinary catalog frame smeared by the camera's rate, solved
lost-in-space from its streaks (issue 19: :func:`startrack.rate._streak_solve.solve_streaked`).

The camera turns at ``rate_deg_s`` about an axis uniform on the sphere (camera frame), plus,
with ``accel_deg_s2``, a constant angular acceleration of that size about another uniform axis;
the exposure makes the streaks ``streak_fraction`` of the field long (uniform in the range per
frame; |omega| T / FoV, Sease 2013 eq. 3.28); the trial's attitude holds at mid-exposure. The
Hipparcos sky to ``max_mag`` at ``epoch_jyear`` is rendered through the ``sensor`` preset (every
Optics / Detector field and ``noise_<field>`` switch is a parameter, as in the image level) with
the rolling-shutter ``line_time_s``. The solver gets the field of view (``fov_known``: trusted to
3 % and its focal length fitted) or searches ``fov_range_deg``, the exposure and line time, and,
with ``prior = "sign"``, a rate of the right sign (a gyro, a commanded slew) that orders the
exposure in time; with ``"none"`` the rate is scored against whichever of +-omega it is nearer
(one frame cannot tell the time order).

Common columns: ``status`` the attitude's (OK, TOO_FEW_STARS, NO_MATCH), the attitude errors of
the mid-exposure attitude against the truth, ``n_stars`` the clean streaks fitted, ``n_matched``
the identified streaks in the joint fit, ``time_s`` the wall time of the solve. Extra columns:
``rate_status`` (OK: a trusted rate; else why not), ``rate_ok``, ``rate_err_pct``
(100 |omega_est - omega| / |omega| of a trusted rate, NaN when refused), ``rate_err_any_pct``
(the same of the fitted rate, trusted or not), ``rate_mag_err_pct`` (signed) and
``axis_err_deg`` (of a trusted rate), ``rate_sigma3_pct`` (the solver's 3-sigma
uncertainty of the rate vector over |omega|), ``rate_sigma_roll_deg_s`` / ``rate_sigma_cross_deg_s``
(its 1-sigma about and across the boresight), ``accel_err_deg_s2`` (with ``fit_alpha``),
``birge``, ``t_mid_err_s`` (the solution's mid-exposure time after the exposure start, minus the
simulator's), ``streak_fraction`` (drawn), ``exposure_s``, ``streak_px`` (the true median streak
length of the stars in the image), ``n_true`` (those stars), ``cpu_s`` (process time of the
solve), ``time_order_known``, ``five_streaks`` (solved with at least five identified streaks: the
frames the issue's target is about), ``meets_target`` (a trusted rate within 1 % and an axis
within 0.5 deg, the target of issue 19 and Sease 2013 ch. 6), ``rate_bound_pct`` (the Cramér-Rao
bound of the rate vector, 1 sigma over |omega|, that the identified streaks allow at the true state:
:func:`startrack.rate.rate_bound`) and ``target_chance`` (the chance that an efficient unbiased
estimator with those streaks meets the target: :func:`startrack.rate.target_chance`) and
``target_chance_trusted`` (the same for an efficient estimator that, like the solver, refuses a rate
whose 3-sigma exceeds ``StreakOptions.max_rate_uncertainty``: 0 where the bound itself is over it).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....camera import Camera
from ....rate import StreakOptions, StreakSolution, axis_error_rad, rate_bound, solve_streaked, target_chance
from ....simulate import SENSOR_PRESETS, FrameTiming, VaryingRate, simulate_frame
from ....units import DEG
from .._outcome import NAN, solution_columns
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS
from ._scene import NOISE_PARAMS, SENSOR_FIELD_PARAMS, frame_noise, frame_sensor
from ._streaks import check_range

FRAME_PARAMS = (
    Param("sensor", "str", "generic-cmos", "the sensor preset (startrack.simulate.SENSOR_PRESETS)",
          choices=tuple(sorted(SENSOR_PRESETS))),
    Param("max_mag", "float", 7.5, "faintest catalog star rendered (V)", lo=-2.0, hi=16.0),
    Param("epoch_jyear", "float", 2025.0, "epoch of the star positions, scene and solver (Julian year, TDB)",
          lo=1900.0, hi=2100.0),
    Param("rate_deg_s", "float", 2.0, "the camera's rate about a uniformly random axis (deg/s)", lo=1e-3, hi=100.0),
    Param("accel_deg_s2", "float", 0.0, "a constant angular acceleration about another random axis (deg/s^2)",
          lo=0.0, hi=1000.0),
    Param("streak_fraction", "floats", (0.05, 0.30), "streak length |omega| T / FoV, uniform in [lo, hi] per frame",
          lo=1e-3, hi=0.9, length=2),
    Param("line_time_s", "float", 0.0, "rolling shutter: delay between rows (s); 0 is a global shutter",
          lo=0.0, hi=1e-2),
)
SOLVER_PARAMS = (
    Param("fov_known", "bool", True, "true: the solver gets fov_deg (trusted to 3 %); false: it searches "
          "fov_range_deg"),
    Param("fov_range_deg", "floats", (5.0, 35.0), "FOV range searched when fov_known is false (deg)",
          lo=0.5, hi=100.0, length=2),
    Param("prior", "str", "sign", 'time order: "sign" gives the solver a rate of the right sign, "none" nothing',
          choices=("sign", "none")),
    Param("fit_alpha", "bool", False, "the solver fits a constant angular acceleration too"),
    Param("lis_streaks", "int", StreakOptions.lis_streaks, "brightest streaks fitted for the identification "
          "(then twice as many when they do not identify)", lo=3, hi=200),
    Param("max_streaks", "int", StreakOptions.max_streaks, "most streaks in the joint fit", lo=3, hi=500),
    Param("catalog_max_mag", "float", StreakOptions.catalog_max_mag,
          "faintest catalog star whose predicted streak is fitted (V)", lo=-2.0, hi=12.0),
)
PARAMS = params_by_name(CAMERA_PARAMS, FRAME_PARAMS, SOLVER_PARAMS, SENSOR_FIELD_PARAMS, NOISE_PARAMS)


def random_axis(rng: np.random.Generator) -> np.ndarray:
    """A unit vector uniform on the sphere."""
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def draw(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator):
    """(simulated frame, omega (rad/s), alpha (rad/s^2), exposure (s), streak fraction) of a trial."""
    camera = Camera.from_fov(params["width"], params["height"], params["fov_deg"])
    omega = params["rate_deg_s"] * DEG * random_axis(rng)
    alpha = params["accel_deg_s2"] * DEG * random_axis(rng)
    fraction = float(rng.uniform(*params["streak_fraction"]))
    exposure = fraction * math.radians(params["fov_deg"]) / np.linalg.norm(omega)
    sensor = frame_sensor({**params, "exposure_s": exposure})
    line = params["line_time_s"]
    start = -0.5 * exposure - 0.5 * (camera.height - 1) * line
    if np.any(alpha):
        profile = VaryingRate.accelerating(rot, omega, alpha)
        sim = simulate_frame(camera, profile, max_mag=params["max_mag"], epoch_jyear=params["epoch_jyear"],
                             sensor=sensor, rng=rng, noise=frame_noise(params),
                             timing=FrameTiming(start_s=start, line_time_s=line))
    else:
        sim = simulate_frame(camera, rot, max_mag=params["max_mag"], epoch_jyear=params["epoch_jyear"], sensor=sensor,
                             rng=rng, noise=frame_noise(params), rate_rad_s=omega,
                             timing=FrameTiming(line_time_s=line))
    return sim, omega, alpha, exposure, fraction


def solver_options(params: Mapping[str, Any]) -> StreakOptions:
    return StreakOptions(fit_alpha=params["fit_alpha"], lis_streaks=params["lis_streaks"],
                         max_streaks=params["max_streaks"], catalog_max_mag=params["catalog_max_mag"],
                         line_time_s=params["line_time_s"])


def rate_scores(solution: StreakSolution, omega: np.ndarray, alpha: np.ndarray) -> dict[str, Any]:
    """Rate error columns of a solution against the true omega (and alpha): those of the trusted
    rate (NaN when refused), and ``rate_err_any_pct`` of whatever rate the fit made."""
    est = solution.turn_rad / solution.exposure_s if solution.solved else np.full(3, np.nan)
    if not np.all(np.isfinite(est)):
        return {"rate_err_pct": NAN, "rate_err_any_pct": NAN, "rate_mag_err_pct": NAN, "axis_err_deg": NAN,
                "accel_err_deg_s2": NAN}
    if not solution.time_order_known and np.dot(est, omega) < 0:
        est = -est
    norm = float(np.linalg.norm(omega))
    error = 100.0 * float(np.linalg.norm(est - omega)) / norm
    trusted = solution.rate.ok
    return {"rate_err_pct": error if trusted else NAN, "rate_err_any_pct": error,
            "rate_mag_err_pct": 100.0 * (float(np.linalg.norm(est)) - norm) / norm if trusted else NAN,
            "axis_err_deg": axis_error_rad(est, omega) / DEG if trusted else NAN,
            "accel_err_deg_s2": float(np.linalg.norm(solution.alpha_rad_s2 - alpha)) / DEG}


def _uncertainty(solution: StreakSolution, omega: np.ndarray) -> dict[str, float]:
    cov = solution.rate.covariance_rad2_s2
    if cov is None or not solution.solved:
        return {"rate_sigma3_pct": NAN, "rate_sigma_roll_deg_s": NAN, "rate_sigma_cross_deg_s": NAN}
    roll, cross = solution.rate_sigma_roll_cross_deg_s
    return {"rate_sigma3_pct": 300.0 * math.sqrt(float(np.trace(cov))) / float(np.linalg.norm(omega)),
            "rate_sigma_roll_deg_s": roll, "rate_sigma_cross_deg_s": cross}


def _bound(solution: StreakSolution, truth, omega: np.ndarray, alpha: np.ndarray,
           options: StreakOptions) -> dict[str, float]:
    """The Cramér-Rao bound of the rate that the frame's identified streaks allow at the true
    state, the chance that an efficient unbiased estimator meets the target with them, and the
    same when that estimator also refuses a rate whose 3-sigma bound exceeds the solver's limit."""
    cov = rate_bound(solution, truth.camera, truth.rot_cam_from_icrs, omega, alpha, fit_alpha=options.fit_alpha)
    if not np.all(np.isfinite(cov)):
        return {"rate_bound_pct": NAN, "target_chance": NAN, "target_chance_trusted": NAN}
    bound = math.sqrt(float(np.trace(cov))) / float(np.linalg.norm(omega))
    chance = target_chance(cov, omega, TARGET_RATE_PCT / 100.0, math.radians(TARGET_AXIS_DEG))
    return {"rate_bound_pct": 100.0 * bound, "target_chance": chance,
            "target_chance_trusted": chance if 3.0 * bound <= options.max_rate_uncertainty else 0.0}


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One streaked catalog frame with its mid-exposure attitude ``rot``, solved and scored."""
    sim, omega, alpha, exposure, fraction = draw(params, rot, rng)
    truth = sim.truth
    fov = {"fov_deg": params["fov_deg"]} if params["fov_known"] else {"fov_range_deg": tuple(params["fov_range_deg"])}
    prior = omega if params["prior"] == "sign" else None
    t0, c0 = time.perf_counter(), time.process_time()
    solution = solve_streaked(sim.image, exposure_s=exposure, epoch=params["epoch_jyear"], prior_omega_rad_s=prior,
                              options=solver_options(params), **fov)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    fitted = solution.streaks
    n_clean = int(fitted.ok.sum()) if fitted is not None else 0
    row = solution_columns(solution, truth.rot_cam_from_icrs, truth.camera, tolerance_px, n_clean)
    row["time_s"] = wall
    inside = truth.inside()
    lengths = truth.streak_length_px[inside]
    row.update(rate_status=solution.rate.status.name, rate_ok=solution.rate.ok and solution.solved,
               birge=solution.birge, streak_fraction=fraction, exposure_s=exposure,
               streak_px=float(np.median(lengths)) if lengths.size else NAN, n_true=int(inside.sum()), cpu_s=cpu,
               time_order_known=solution.time_order_known,
               t_mid_err_s=solution.t_mid_s - (truth.t_mid_s - (-0.5 * exposure - 0.5 * (truth.camera.height - 1)
                                                                  * params["line_time_s"])),
               **rate_scores(solution, omega, alpha), **_uncertainty(solution, omega),
               **_bound(solution, truth, omega, alpha, solver_options(params)))
    row.update(five_streaks=bool(solution.solved and solution.n_streaks >= TARGET_STREAKS),
               meets_target=bool(row["rate_ok"] and row["rate_err_pct"] <= TARGET_RATE_PCT
                                 and row["axis_err_deg"] <= TARGET_AXIS_DEG))
    return TrialOutput(row, image=sim.image, truth=truth)


TARGET_STREAKS, TARGET_RATE_PCT, TARGET_AXIS_DEG = 5, 1.0, 0.5
"""Issue 19's target: every frame with 5 identified streaks gives a rate within 1 % and an axis within 0.5 deg."""


def check(params: Mapping[str, Any]) -> None:
    """Refuse empty ranges and a sensor or noise setting the simulator refuses."""
    check_range(params, "streak_fraction")
    check_range(params, "fov_range_deg")
    try:
        frame_sensor({**params, "exposure_s": 1.0})
        frame_noise(params)
    except (ValueError, TypeError) as exc:
        raise SpecError(f"sensor settings: {exc}") from None


COLUMNS = {"rate_status": pa.string(), "rate_ok": pa.bool_(), "rate_err_pct": pa.float64(),
           "rate_err_any_pct": pa.float64(),
           "rate_mag_err_pct": pa.float64(), "axis_err_deg": pa.float64(), "accel_err_deg_s2": pa.float64(),
           "rate_sigma3_pct": pa.float64(), "rate_sigma_roll_deg_s": pa.float64(),
           "rate_sigma_cross_deg_s": pa.float64(), "birge": pa.float64(), "t_mid_err_s": pa.float64(),
           "streak_fraction": pa.float64(), "exposure_s": pa.float64(), "streak_px": pa.float64(),
           "n_true": pa.int32(), "cpu_s": pa.float64(), "time_order_known": pa.bool_(),
           "five_streaks": pa.bool_(), "meets_target": pa.bool_(), "rate_bound_pct": pa.float64(),
           "target_chance": pa.float64(), "target_chance_trusted": pa.float64()}

LEVEL = register(Level(
    name="streak_frames", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns=COLUMNS, chunk_trials=4))
