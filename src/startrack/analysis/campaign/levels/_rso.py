"""Level "rso": one streaked frame, its catalog-free rate and the three RSO indicators
(Sease 2013 ch. 4: Tables 4.1, 4.2 and, with ``scenario = "orbits"``, Tables 4.3-4.4).

Scenario "slew" (Tables 4.1, 4.2): the camera turns at ``rate_rad_s`` about ``axis`` (camera
frame) from the trial's attitude; with ``rso = true`` the frame also holds a satellite of V
magnitude ``rso_mag`` whose sight line turns across the sky at ``rso_own_range`` times the
camera's rate in a random direction (:func:`startrack.analysis._streak_scenes.turning_rso_snapshot`;
an assumption: the seed's two examples give no geometry). Scenario "orbits" (Tables 4.3-4.4):
frame ``opportunity`` of the observation opportunities of the seed's 10-orbit simulation
(:func:`startrack.analysis._rso_passes.find_passes`): the Table 4.3 orbits (``camera_elements``,
``rso_elements`` at ``epoch_utc``, propagated with J2), the camera turning at ``rate_rad_s``
about ``axis`` from the identity attitude at the epoch (the trial's attitude is not used), and
the RSO where the orbits put it. In both, ``stars`` stars are placed where their paths stay in
the image and apart from each other (``gap_px``) and ``rso_gap_px`` from the RSO's path (which
also stays ``rso_gap_px`` inside the image): a lost or overlapping RSO would be a segmentation
matter, not one of the indicators (so the seed's "overlapping streak" column is always 0 here).

:func:`startrack.rate._streak_rate.streak_rate` measures the streaks (``detector``, ``bias_px``),
the catalog-free OLAE rate (time order from the true rate as the prior, as a commanded slew would
give) and the indicators at ``k_sigma``. The RSO's streak is the measured one whose two ends lie
within 3 px of the RSO's true ends (either way round); the indicators "find" it when they flag
that streak, and each star streak they flag is a false detection.

Common columns (no attitude): ``status`` the rate's status (OK, TOO_FEW_STARS, DEGENERATE...);
``solved`` a rate was returned; ``correct`` it is within ``rate_tolerance_pct`` of the truth;
``n_stars`` the streaks measured, ``n_matched`` those the rate used; ``time_s`` the measurement and
rate; the attitude errors NaN; ``ra_deg``, ``dec_deg``, ``roll_deg`` the attitude at the start of
the exposure. Extra columns: the estimated rate (``rate_est_rad_s``, ``rate_est_deg_s``), the
displacement over the exposure (``displacement_rad``, ``displacement_deg``), ``rate_err_pct``
(100 |omega_est - omega| / |omega|), ``rate_mag_err_pct`` (signed, of the magnitude),
``axis_err_deg``, the estimated unit axis ``axis_x``, ``axis_y``, ``axis_z``; ``rso_present``,
``rso_measured``, ``found_<indicator>`` and ``false_<indicator>`` for the indicators
centre_of_rotation, angular_displacement and combined (seed: "Magnitude of Rotation" is the
angular displacement, "Combined" the OLAE residual), ``rso_z_<indicator>`` (the RSO streak's |z|
under each; the seed quotes 3.6, 3.5 and 3.6 sigma for Table 4.2's RSO), ``n_star_streaks``,
``rso_own_motion_px`` (how far the RSO's end is from where a star starting at its place would
end), ``rso_range_km``, ``start_s`` (from the epoch) and ``opportunities`` (of the scenario;
0 for "slew").
"""

from __future__ import annotations

import functools
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ....errors import InvalidInputError
from ....rate import DETECTORS, INDICATORS, SEGMENT, RateEstimate, StreakRate, axis_error_rad, streak_rate
from ....units import DEG
from ..._rso_passes import SEASE2013_CAMERA_ELEMENTS, SEASE2013_RSO_ELEMENTS, Pass, elements, find_passes
from ..._streak_scenes import StreakScene, rso_path, separated_field, star_field, turning_rso_snapshot
from .._outcome import NAN
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._measure import measurement_columns
from ._streaks import STREAK_CAMERA_PARAMS, STREAK_SCENE_PARAMS, check_range, render, star_flux, streak_camera

RSO_MATCH_PX = 3.0
"""A measured streak is the RSO's when both its ends lie this close to the RSO's true ends."""

RSO_PARAMS = (
    Param("scenario", "str", "slew", 'slew: constant rate from the trial\'s attitude (Tables 4.1-4.2); '
          'orbits: the Table 4.3 orbits (Table 4.4)', choices=("slew", "orbits")),
    Param("exposure_s", "float", 0.5, "exposure (s); also the frame interval of the orbit scenario",
          lo=1e-3, hi=100.0),
    Param("rate_rad_s", "float", 0.05, "the camera's rate (rad/s)", lo=1e-4, hi=10.0),
    Param("axis", "floats", (0.0, 1.0, 0.0), "the rate's axis, camera frame (normalised)", lo=-1.0, hi=1.0,
          length=3),
    Param("stars", "int", 15, "star streaks in the frame", lo=2, hi=200),
    Param("rso", "bool", True, "slew scenario: the frame holds an RSO"),
    Param("rso_mag", "float", 4.0, "the RSO's V magnitude (seed: 1 in Table 4.2, 4 in the 10-orbit run)",
          lo=-5.0, hi=20.0),
    Param("rso_own_range", "floats", (0.2, 0.8), "slew scenario: the RSO's own angular rate across the sky, "
          "uniform in [lo, hi] times the camera's rate", lo=0.0, hi=10.0, length=2),
    Param("rso_gap_px", "float", 30.0, "the RSO's path stays this far from every star path and from the "
          "border (px)", lo=0.0, hi=1000.0),
    Param("detector", "str", SEGMENT, "endpoint method (docs/attitude_and_rate.md)", choices=(SEGMENT, *DETECTORS)),
    Param("bias_px", "float", 0.0, "inward bias of a corner detector's ends (px)", lo=-10.0, hi=10.0),
    Param("k_sigma", "float", 2.5, "outlier threshold of the indicators and the OLAE rejection (sigma)",
          lo=0.5, hi=100.0),
    Param("rate_tolerance_pct", "float", 5.0, "a rate is correct within this share of |omega| (%)",
          lo=0.0, hi=1000.0),
    Param("camera_elements", "floats", SEASE2013_CAMERA_ELEMENTS, "orbit scenario: the camera spacecraft's "
          "a (km), e, i, RAAN, argp, true anomaly (deg) (Table 4.3)", lo=-360.0, hi=1e6, length=6),
    Param("rso_elements", "floats", SEASE2013_RSO_ELEMENTS, "orbit scenario: the RSO's elements (Table 4.3)",
          lo=-360.0, hi=1e6, length=6),
    Param("epoch_utc", "str", "2013-01-01T00:00:00", "orbit scenario: epoch of the elements and the identity "
          "attitude (ISO, UTC; the seed gives none)"),
    Param("orbits", "float", 10.0, "orbit scenario: length in periods of the camera's orbit", lo=0.01, hi=1000.0),
    Param("opportunity", "int", 0, "orbit scenario: which observation opportunity (0-based, time order)",
          lo=0, hi=100000),
)

PARAMS = params_by_name(STREAK_CAMERA_PARAMS, STREAK_SCENE_PARAMS, RSO_PARAMS)
PASS_KEYS = ("fov_deg", "width", "height", "camera_elements", "rso_elements", "epoch_utc", "orbits",
             "rate_rad_s", "axis", "exposure_s", "rso_mag", "rso_gap_px")


def omega_of(params: Mapping[str, Any]) -> np.ndarray:
    """The camera's rate vector (camera frame, rad/s)."""
    axis = np.asarray(params["axis"], dtype=float)
    return params["rate_rad_s"] * axis / np.linalg.norm(axis)


@functools.lru_cache(maxsize=4)
def _passes(items: tuple) -> tuple[Pass, ...]:
    p = dict(items)
    return tuple(find_passes(streak_camera(p), elements(p["camera_elements"], "camera_elements"),
                             elements(p["rso_elements"], "rso_elements"), Time(p["epoch_utc"], scale="utc"),
                             omega_cam_rad_s=omega_of(p), exposure_s=p["exposure_s"], orbits=p["orbits"],
                             rso_mag=p["rso_mag"], margin_px=p["rso_gap_px"]))


def passes(params: Mapping[str, Any]) -> tuple[Pass, ...]:
    """The observation opportunities of the cell's orbit scenario (computed once per process)."""
    return _passes(tuple((k, params[k]) for k in PASS_KEYS))


def _slew_rso(params: Mapping[str, Any], rot: Rotation, omega: np.ndarray, rng: np.random.Generator):
    """A turning RSO whose path stays ``rso_gap_px`` inside the image: (snapshot, path)."""
    camera, exposure = streak_camera(params), params["exposure_s"]
    for _ in range(100):
        v0 = star_field(camera, omega, exposure, 1, rng, margin_px=params["rso_gap_px"])[0]
        side = np.cross(v0, rng.normal(size=3))
        own = rng.uniform(*params["rso_own_range"]) * params["rate_rad_s"] * side / np.linalg.norm(side)
        snapshot = turning_rso_snapshot(rot, v0, own, exposure, params["rso_mag"])
        path = rso_path(camera, rot, omega, exposure, snapshot)
        if np.all(camera.in_image(path[:, 0], path[:, 1], params["rso_gap_px"])):
            return snapshot, path
    raise InvalidInputError("no RSO path inside the image in 100 draws: lower rso_own_range or rso_gap_px")


def draw_frame(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator) -> tuple[StreakScene, Pass | None]:
    """The frame of a trial (module docstring) and its opportunity (orbit scenario)."""
    omega, exposure, chosen = omega_of(params), params["exposure_s"], None
    snapshot = path = None
    if params["scenario"] == "orbits":
        chosen = passes(params)[params["opportunity"]]
        rot, snapshot = chosen.rot_start, chosen.snapshot
        path = rso_path(streak_camera(params), rot, omega, exposure, snapshot)
    elif params["rso"]:
        snapshot, path = _slew_rso(params, rot, omega, rng)
    vectors = separated_field(streak_camera(params), omega, exposure, params["stars"], rng,
                              margin_px=params["margin_px"], gap_px=params["gap_px"], avoid_xy=path,
                              avoid_px=params["rso_gap_px"])
    flux = star_flux(params, params["stars"], rng)
    return render(params, rot, omega, exposure, vectors, flux, rng, rso=snapshot), chosen


def rso_streak(scene: StreakScene, ends_a: np.ndarray, ends_b: np.ndarray) -> int | None:
    """Index of the measured streak whose ends are the RSO's (either way round), or None."""
    if not scene.is_rso[-1] or not len(ends_a):
        return None
    truth = np.stack([scene.start_xy[-1], scene.end_xy[-1]])
    ends = np.stack([ends_a, ends_b], axis=1)  # (N, 2, 2)
    misfit = np.minimum(np.max(np.linalg.norm(ends - truth, axis=2), axis=1),
                        np.max(np.linalg.norm(ends - truth[::-1], axis=2), axis=1))
    best = int(np.argmin(misfit))
    return best if misfit[best] <= RSO_MATCH_PX else None


def rate_columns(estimate: RateEstimate, omega: np.ndarray, exposure_s: float) -> dict[str, Any]:
    """The estimated rate, displacement, errors and unit axis of a rate estimate (NaN when none)."""
    est = np.asarray(estimate.omega_rad_s, dtype=float)
    if not estimate.ok:
        names = ("rate_est_rad_s", "rate_est_deg_s", "displacement_rad", "displacement_deg", "rate_err_pct",
                 "rate_mag_err_pct", "axis_err_deg", "axis_x", "axis_y", "axis_z")
        return dict.fromkeys(names, NAN)
    size, true = float(np.linalg.norm(est)), float(np.linalg.norm(omega))
    axis = est / size
    return {"rate_est_rad_s": size, "rate_est_deg_s": size / DEG, "displacement_rad": size * exposure_s,
            "displacement_deg": size * exposure_s / DEG,
            "rate_err_pct": 100.0 * float(np.linalg.norm(est - omega)) / true,
            "rate_mag_err_pct": 100.0 * (size - true) / true, "axis_err_deg": axis_error_rad(est, omega) / DEG,
            "axis_x": float(axis[0]), "axis_y": float(axis[1]), "axis_z": float(axis[2])}


def indicator_columns(scene: StreakScene, result: StreakRate) -> dict[str, Any]:
    """Whether each indicator flagged the RSO's streak, and how many star streaks it flagged."""
    meas = result.measurement
    index = rso_streak(scene, meas.ends_a, meas.ends_b)
    others = np.ones(len(meas.ends_a), dtype=bool)
    if index is not None:
        others[index] = False
    row: dict[str, Any] = {"rso_present": bool(scene.is_rso[-1]), "rso_measured": index is not None,
                           "n_star_streaks": int(others.sum())}
    for name in INDICATORS:
        flags = result.rso.flags[name] if result.rso is not None else np.zeros(len(others), dtype=bool)
        row[f"found_{name}"] = bool(index is not None and flags[index])
        row[f"false_{name}"] = int(np.sum(flags[others]))
        row[f"rso_z_{name}"] = float(abs(result.rso.z[name][index])) if index is not None and result.rso else NAN
    return row


def own_motion_px(scene: StreakScene) -> float:
    """Distance (px) of the RSO's true end from where a star starting at its place would end."""
    if not scene.is_rso[-1]:
        return NAN
    x, y = scene.camera.vector_to_pixel(scene.rot_end.apply(scene.icrs[-1]))
    return float(np.hypot(x - scene.end_xy[-1, 0], y - scene.end_xy[-1, 1]))


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One frame (``rot``: its attitude at the start in the slew scenario), rate and indicators."""
    scene, chosen = draw_frame(params, rot, rng)
    omega = scene.omega_rad_s
    t0 = time.perf_counter()
    result = streak_rate(scene.image, scene.camera, scene.exposure_s, detector=params["detector"],
                         bias_px=params["bias_px"], prior_omega_rad_s=omega, k_sigma=params["k_sigma"])
    elapsed = time.perf_counter() - t0
    rates = rate_columns(result.rate, omega, scene.exposure_s)
    correct = bool(result.rate.ok and rates["rate_err_pct"] <= params["rate_tolerance_pct"])
    used = result.rate.used
    row = measurement_columns(status=result.rate.status.name, correct=correct, n_stars=len(result.measurement.ends_a),
                              n_matched=int(np.sum(used)) if used is not None else 0, time_s=elapsed,
                              rot_cam_from_icrs=scene.rot_start)
    row["solved"] = bool(result.rate.ok)
    row.update(rates, **indicator_columns(scene, result), rso_own_motion_px=own_motion_px(scene),
               rso_range_km=chosen.range_km if chosen is not None else NAN,
               start_s=chosen.start_s if chosen is not None else 0.0,
               opportunities=len(passes(params)) if chosen is not None else 0)
    return TrialOutput(row, image=scene.image, truth=scene.truth)


def check(params: Mapping[str, Any]) -> None:
    """Refuse empty ranges, a zero axis, a bad epoch or orbit, and an opportunity the scenario lacks."""
    for name in ("star_electrons", "rso_own_range"):
        check_range(params, name)
    if np.linalg.norm(params["axis"]) < 1e-6:
        raise SpecError("axis: must not be the zero vector")
    if params["scenario"] != "orbits":
        return
    try:
        Time(params["epoch_utc"], scale="utc")
        found = passes(params)
    except (ValueError, InvalidInputError) as exc:
        raise SpecError(f"orbit scenario: {exc}") from None
    if params["opportunity"] >= len(found):
        raise SpecError(f"opportunity: the orbit scenario has {len(found)} observation opportunities "
                        f"(0 to {len(found) - 1}), got {params['opportunity']}")


COLUMNS: dict[str, pa.DataType] = {
    **dict.fromkeys(("rate_est_rad_s", "rate_est_deg_s", "displacement_rad", "displacement_deg", "rate_err_pct",
                     "rate_mag_err_pct", "axis_err_deg", "axis_x", "axis_y", "axis_z"), pa.float64()),
    "rso_present": pa.bool_(), "rso_measured": pa.bool_(), "n_star_streaks": pa.int32(),
    **{f"found_{name}": pa.bool_() for name in INDICATORS}, **{f"false_{name}": pa.int32() for name in INDICATORS},
    **{f"rso_z_{name}": pa.float64() for name in INDICATORS},
    "rso_own_motion_px": pa.float64(), "rso_range_km": pa.float64(), "start_s": pa.float64(),
    "opportunities": pa.int32(),
}

def warm_key(params: Mapping[str, Any]) -> dict[str, Any]:
    """Cells that differ only in the opportunity they pick share one warm-up."""
    return {k: v for k, v in params.items() if k != "opportunity"}


LEVEL = register(Level(
    name="rso", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns=COLUMNS, chunk_trials=2,
    warm_key=warm_key))
