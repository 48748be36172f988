"""Level "streak": one streaked frame, its streak ends located by a corner detector, and the
attitudes at both ends and the rate between them (Sease 2013 ch. 3, Table 3.1).

The camera spins at ``rate_rad_s`` about an axis ``theta`` from the boresight (uniform in
``theta_range_deg``, the seed's "precise region" by default) at a uniform azimuth; the exposure
makes streaks ``streak_fraction`` of the field long (the seed's %FoV = |omega| T / FoV, eq. 3.28).
The stars are placed where their paths stay in the image and apart (``gap_px``), with electrons
in ``star_electrons`` scaled by ``streak_fraction / 0.1`` above 10 % (the same signal per pixel
of streak), and rendered at the trial's attitude (the start of the exposure) by
:func:`startrack.analysis._streak_scenes.render_streak_scene`.
:func:`startrack.rate._streak_rate.measure_streaks` finds the ends with ``detector`` and the
bias ``bias_px``: "auto" calibrates the detector's inward bias, with its direction dependence
(:func:`startrack.rate._endpoints.calibrate_bias_model`), on ``calibration_frames`` separate
frames at 10 % streak length drawn from ``calibration_seed`` (once per process: the same for
every trial, whatever the worker). Each measured streak takes the true star of the nearest
midpoint, which also orders its ends in time (the seed resolves the order by a-priori knowledge).
The attitudes at both ends come from those identities (ESOQ2, seed eq. 3.23) and the rate from
them (:func:`startrack.rate.rate_between`).

Common columns: ``status`` "OK" when two or more streaks have two clean ends (else
TOO_FEW_STARS); the attitude errors are those of the attitude at the start of the exposure
against the simulator's truth (``correct`` within the campaign's tolerance); ``n_stars`` the
streaks measured, ``n_matched`` the same (every measured streak is scored, a wrong one included);
``false_match_prob`` NaN (no identification); ``time_s`` the streak measurement. Extra columns:
``endpoint_err_px`` (the seed's "single-endpoint attitude error" e = Phi Res / FoV, eq. 3.29, as
the mean pixel distance of the frame's ends from the truth), ``endpoint_max_px``,
``rate_err_pct`` (100 |omega_est - omega| / |omega|), ``axis_err_deg``, ``theta_deg``,
``exposure_s``, ``n_true`` (stars rendered) and ``bias_px`` (the constant part of the bias used).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....rate import (
    DETECTORS,
    SEGMENT,
    EndpointBias,
    attitudes_from_matches,
    axis_error_rad,
    calibrate_bias_model,
    measure_streaks,
    rate_between,
)
from ....units import DEG
from ..._streak_scenes import StreakScene, separated_field, spin_rate
from .._outcome import NAN, error_columns, truth_columns
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._streaks import STREAK_CAMERA_PARAMS, STREAK_SCENE_PARAMS, check_range, in_time_order, render, star_flux
from ._streaks import streak_camera as camera_of

CALIBRATION_FRACTION = 0.1
"""Streak length of the calibration frames (fraction of the field)."""
CALIBRATION_STARS = 10

STREAK_PARAMS = (
    Param("detector", "str", "harris", "endpoint detector (Sease 2013 §3: Harris, minimum eigenvalue, Trajkovic "
          "4 / 8; or the segment fit)", choices=(*DETECTORS, SEGMENT)),
    Param("streak_fraction", "float", 0.1, "streak length |omega| T / FoV (seed eq. 3.28)", lo=0.01, hi=0.9),
    Param("rate_rad_s", "float", 0.05, "the camera's rate (rad/s); the exposure sets the streak length",
          lo=1e-4, hi=10.0),
    Param("theta_range_deg", "floats", (30.0, 90.0), "spin axis angle from the boresight, uniform in "
          "[lo, hi] (deg)", lo=0.0, hi=90.0, length=2),
    Param("stars", "int", None, 'stars in the frame; "auto": 10 below 30 % streak length, else 4',
          lo=2, hi=200, optional=True),
    Param("bias_px", "float", None, 'inward bias of the ends (px); "auto": calibrated (module docstring)',
          lo=-10.0, hi=10.0, optional=True),
    Param("calibration_frames", "int", 6, "frames the bias is calibrated on", lo=1, hi=1000),
    Param("calibration_seed", "int", 31, "seed of the calibration frames' generator", lo=0, hi=2**63 - 1),
)

PARAMS = params_by_name(STREAK_CAMERA_PARAMS, STREAK_SCENE_PARAMS, STREAK_PARAMS)
SCENE_KEYS = tuple(name for name in PARAMS if name not in ("detector", "streak_fraction", "stars", "bias_px"))
"""The parameters the calibration frames depend on."""


def star_count(params: Mapping[str, Any], fraction: float) -> int:
    """Stars in a frame of streaks ``fraction`` of the field long."""
    if params["stars"] is not None:
        return int(params["stars"])
    return 10 if fraction < 0.3 else 4


def draw_frame(params: Mapping[str, Any], rot_start: Rotation, rng: np.random.Generator, fraction: float,
               stars: int) -> StreakScene:
    """A frame of ``stars`` streaks ``fraction`` of the field long (module docstring)."""
    camera = camera_of(params)
    lo, hi = params["theta_range_deg"]
    omega = spin_rate(rng.uniform(lo, hi) * DEG, params["rate_rad_s"], rng.uniform(0.0, 2.0 * math.pi))
    exposure = fraction * math.radians(params["fov_deg"]) / params["rate_rad_s"]
    vectors = separated_field(camera, omega, exposure, stars, rng, margin_px=params["margin_px"],
                              gap_px=params["gap_px"])
    flux = star_flux(params, stars, rng, max(fraction / CALIBRATION_FRACTION, 1.0))
    return render(params, rot_start, omega, exposure, vectors, flux, rng)


@functools.lru_cache(maxsize=8)
def _calibration_frames(scene_items: tuple) -> tuple[StreakScene, ...]:
    params = dict(scene_items) | {"stars": None}
    rng = np.random.default_rng(params["calibration_seed"])
    return tuple(draw_frame(params, Rotation.random(random_state=rng), rng, CALIBRATION_FRACTION,
                            CALIBRATION_STARS) for _ in range(params["calibration_frames"]))


@functools.lru_cache(maxsize=32)
def _calibrated(detector: str, scene_items: tuple) -> EndpointBias:
    measured, truth = [], []
    for scene in _calibration_frames(scene_items):
        meas = measure_streaks(scene.image, scene.camera, detector=detector, bias_px=0.0)
        if len(meas.ends_a):
            index, starts, ends = in_time_order(scene, meas.ends_a, meas.ends_b)
            measured.append(np.stack([starts, ends], axis=1))
            truth.append(np.stack([scene.start_xy[index], scene.end_xy[index]], axis=1))
    if not measured:
        raise SpecError(f"bias_px: no streak of the calibration frames was measured by {detector!r}; "
                        "give bias_px a number")
    return calibrate_bias_model(np.concatenate(measured), np.concatenate(truth))


def endpoint_bias(params: Mapping[str, Any]) -> float | EndpointBias:
    """The bias the cell's detector corrects: ``bias_px``, or the calibrated model (cached)."""
    if params["bias_px"] is not None:
        return float(params["bias_px"])
    return _calibrated(params["detector"], tuple((k, params[k]) for k in SCENE_KEYS))


def _scores(scene: StreakScene, meas, exposure: float) -> dict[str, Any]:
    """Endpoint errors (px), the attitude at the start and the rate errors of a measurement."""
    index, starts, ends = in_time_order(scene, meas.ends_a, meas.ends_b)
    errors = np.concatenate([np.linalg.norm(starts - scene.start_xy[index], axis=1),
                             np.linalg.norm(ends - scene.end_xy[index], axis=1)])
    camera = scene.camera
    rot_a, rot_b = attitudes_from_matches(camera.pixel_to_vector(*starts.T), camera.pixel_to_vector(*ends.T),
                                          scene.icrs[index])
    omega_est = rate_between(rot_a, rot_b, exposure)
    omega = scene.omega_rad_s
    return {"rot_start_est": rot_a, "endpoint_err_px": float(np.mean(errors)), "endpoint_max_px": float(np.max(errors)),
            "rate_err_pct": float(100.0 * np.linalg.norm(omega_est - omega) / np.linalg.norm(omega)),
            "axis_err_deg": float(axis_error_rad(omega_est, omega) / DEG)}


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One streaked frame starting at ``rot`` (``rot_cam_from_icrs``), measured and scored."""
    fraction = params["streak_fraction"]
    bias = endpoint_bias(params)
    scene = draw_frame(params, rot, rng, fraction, star_count(params, fraction))
    t0 = time.perf_counter()
    meas = measure_streaks(scene.image, scene.camera, detector=params["detector"], bias_px=bias)
    elapsed = time.perf_counter() - t0
    theta = math.degrees(math.atan2(math.hypot(*scene.omega_rad_s[:2]), scene.omega_rad_s[2]))
    extra = {"theta_deg": theta, "exposure_s": scene.exposure_s, "n_true": len(scene.icrs), "bias_px": float(bias)}
    n = len(meas.ends_a)
    if n < 2:
        row = {"status": "TOO_FEW_STARS", "solved": False, **error_columns(scene.rot_start, None, scene.camera, 0.0),
               "endpoint_err_px": NAN, "endpoint_max_px": NAN, "rate_err_pct": NAN, "axis_err_deg": NAN}
    else:
        scores = _scores(scene, meas, scene.exposure_s)
        row = {"status": "OK", "solved": True,
               **error_columns(scene.rot_start, scores.pop("rot_start_est"), scene.camera, tolerance_px), **scores}
    row.update(error="", sigma_cross_arcsec=NAN, sigma_roll_arcsec=NAN, n_stars=n, n_matched=n,
               false_match_prob=NAN, time_s=elapsed, **truth_columns(scene.rot_start), **extra)
    return TrialOutput(row, image=scene.image, truth=scene.truth)


def check(params: Mapping[str, Any]) -> None:
    """Refuse an empty spin-axis range."""
    check_range(params, "theta_range_deg")
    check_range(params, "star_electrons")


COLUMNS = {"endpoint_err_px": pa.float64(), "endpoint_max_px": pa.float64(), "rate_err_pct": pa.float64(),
           "axis_err_deg": pa.float64(), "theta_deg": pa.float64(), "exposure_s": pa.float64(),
           "n_true": pa.int32(), "bias_px": pa.float64()}

LEVEL = register(Level(
    name="streak", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns=COLUMNS, chunk_trials=4))
