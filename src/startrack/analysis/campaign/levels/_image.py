"""Level "image": render a frame of the Hipparcos sky (:func:`startrack.simulate.simulate_frame`),
detect its stars (:class:`startrack.detect.StarDetector`) and solve them lost-in-space.

Every simulator and detector setting is a parameter (:mod:`._scene`). The solver gets the true
camera when ``calibrated`` (without its radial distortion when ``distortion_known`` is false),
else the FOV (``fov_known``) or the FOV range; its catalog is at ``solver_epoch_jyear`` ("auto":
the scene's ``epoch_jyear``). The frame may show stellar aberration (``aberration_annual``,
``aberration_velocity_km_s``, :mod:`._scene`). The attitude is judged against the true attitude at
the frame's time tag: mid-exposure plus ``timing_error_s`` (the truth carried there with the
camera's rate). With ``frames_per_attitude`` N > 0, trial k of every cell looks at star field
k // (N D) (D = ``attitudes_per_field``), turned by dither k // N mod D of up to ``dither_px``
pixels, in N frames with independent noise: the cells share their attitudes, and repeated and
dithered frames of one field separate temporal noise from spatial errors (``docs/error_budget.md``).
Extra columns: the per-stage times ``time_render_s``,
``time_detect_s``, ``time_identify_s``; ``n_truth`` (stars centred in the image), and
``centroid_rms_px``, the RMS distance from each true star to its nearest detection within 2 px
(the centroid error, whatever the identification did).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ....frames import random_rotations
from ....results import Detections
from ....simulate import ConstantRate, FrameTiming, simulate_frame
from ....solve import solve_stars
from .._outcome import solution_columns
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS, SOLVER_PARAMS, check_solver
from ._scene import (
    APPARENT_PARAMS,
    DETECT_PARAMS,
    FRAME_PARAMS,
    NOISE_PARAMS,
    SENSOR_FIELD_PARAMS,
    check_scene,
    frame_camera,
    frame_detector,
    frame_noise,
    frame_rate_rad_s,
    frame_sensor,
    frame_sky,
    frame_sky_model,
)

ERROR_PARAMS = (
    Param("solver_epoch_jyear", "float", None, "epoch of the catalog the solver uses (Julian year, TDB); "
          "auto: the scene's epoch_jyear (1991.25: Hipparcos as published, no proper motion)",
          lo=1900.0, hi=2100.0, optional=True),
    Param("distortion_known", "bool", True, "with calibrated: the solver knows the lens's radial distortion; "
          "false: it gets the true focal lengths and principal point with k1 = k2 = k3 = 0"),
    Param("timing_error_s", "float", 0.0, "error of the frame's time tag (s): the solution is judged against "
          "the true attitude at mid-exposure + timing_error_s (carried there with the camera rate)",
          lo=-100.0, hi=100.0),
    Param("frames_per_attitude", "int", 0, "0: each trial its own attitude (the campaign's); N: the cells share "
          "attitudes and N consecutive trials look at one attitude with independent noise", lo=0, hi=1_000_000),
    Param("attitudes_per_field", "int", 1, "with frames_per_attitude: dithered attitudes per star field "
          "(each turned by up to dither_px pixels from the field's)", lo=1, hi=1_000_000),
    Param("dither_px", "float", 1.0, "width (px) of the square over which the dithers move the field "
          "(1: every sub-pixel phase)", lo=0.0, hi=1000.0),
)
ATTITUDE_STREAM = 2**32 - 1
"""First spawn-key word of the shared attitudes' streams: ``SeedSequence(seed, spawn_key=
(ATTITUDE_STREAM, field))`` and ``(ATTITUDE_STREAM, field, dither)`` (no cell index reaches it)."""

PARAMS = params_by_name(CAMERA_PARAMS, FRAME_PARAMS, APPARENT_PARAMS, SENSOR_FIELD_PARAMS, NOISE_PARAMS,
                        DETECT_PARAMS, SOLVER_PARAMS, ERROR_PARAMS)
MATCH_PX = 2.0
"""Largest distance (px) at which a detection counts as the centroid of a true star."""


def image_solver_kwargs(params: Mapping[str, Any], camera) -> dict[str, Any]:
    """The solver's knowledge of the camera (all of it, all but its radial distortion, its FOV, or a
    FOV range) and of the catalog epoch."""
    if params["calibrated"]:
        known = params.get("distortion_known", True)
        knowledge = {"camera": camera if known else camera.with_distortion(k1=0.0, k2=0.0, k3=0.0)}
    elif params["fov_known"]:
        knowledge = {"fov_deg": camera.fov_deg, "width": camera.width, "height": camera.height}
    else:
        knowledge = {"fov_range_deg": tuple(params["fov_range_deg"]), "width": camera.width, "height": camera.height}
    epoch = params.get("solver_epoch_jyear")
    return {**knowledge, "method": params["method"], "epoch": params["epoch_jyear"] if epoch is None else epoch}


def centroid_rms_px(found: Detections, x_true: np.ndarray, y_true: np.ndarray) -> float:
    """RMS distance (px) from each true star to its nearest detection within :data:`MATCH_PX`."""
    if len(found) == 0 or x_true.size == 0:
        return float("nan")
    dist, _ = cKDTree(np.column_stack([found.x, found.y])).query(np.column_stack([x_true, y_true]),
                                                                 distance_upper_bound=MATCH_PX)
    near = dist[np.isfinite(dist)]
    return float(np.sqrt(np.mean(near**2))) if near.size else float("nan")


def render(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator):
    """The simulated frame of a trial (image and truth)."""
    camera = frame_camera(params)
    return simulate_frame(camera, rot, max_mag=params["max_mag"], epoch_jyear=params["epoch_jyear"],
                          sensor=frame_sensor(params), rng=rng, noise=frame_noise(params),
                          rate_rad_s=frame_rate_rad_s(params), timing=FrameTiming(line_time_s=params["line_time_s"]),
                          sky_background=frame_sky(params), sky=frame_sky_model(params))


def trial_key(rng: np.random.Generator) -> tuple[int, int, int] | None:
    """(seed, cell, trial) of a trial's own stream (``trials.trial_rng``: ``SeedSequence(seed,
    spawn_key=(cell, trial))``), or None for any other generator (a worker's warm-up)."""
    seq = getattr(rng.bit_generator, "seed_seq", None)
    if not isinstance(seq, np.random.SeedSequence) or len(seq.spawn_key) != 2 or not isinstance(seq.entropy, int):
        return None
    return seq.entropy, int(seq.spawn_key[0]), int(seq.spawn_key[1])


def field_and_dither(trial: int, params: Mapping[str, Any]) -> tuple[int, int]:
    """The star field and the dither of trial ``trial`` when ``frames_per_attitude`` > 0."""
    n, d = params["frames_per_attitude"], params["attitudes_per_field"]
    return trial // (n * d), (trial // n) % d


def trial_attitude(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, camera) -> Rotation:
    """The campaign's attitude ``rot``, or with ``frames_per_attitude`` the shared one of the trial's
    field and dither (uniform on SO(3), then turned by a uniform offset of up to +-dither_px / 2
    pixels on each image axis)."""
    key = trial_key(rng)
    if not params.get("frames_per_attitude") or key is None:
        return rot
    seed, _, trial = key
    field, dither = field_and_dither(trial, params)
    out = random_rotations(rng=np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(ATTITUDE_STREAM, field))))
    if params["attitudes_per_field"] == 1 or params["dither_px"] == 0.0:
        return out
    dx, dy = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(ATTITUDE_STREAM, field, dither))
                                   ).uniform(-0.5, 0.5, 2) * params["dither_px"]
    return Rotation.from_rotvec([dy / camera.fy, -dx / camera.fx, 0.0]) * out


def tagged_truth(truth, timing_error_s: float) -> Rotation:
    """The true attitude at the frame's time tag: mid-exposure + ``timing_error_s`` with the rate."""
    if timing_error_s == 0.0:
        return truth.rot_cam_from_icrs
    return ConstantRate(truth.rot_cam_from_icrs, truth.rate_cam_rad_s).attitudes([timing_error_s])[0]


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """Render, detect and solve one frame at ``rot`` (mid-exposure ``rot_cam_from_icrs``)."""
    rot = trial_attitude(params, rot, rng, frame_camera(params))
    t0 = time.perf_counter()
    sim = render(params, rot, rng)
    t1 = time.perf_counter()
    found = frame_detector(params).detect(sim.image)
    t2 = time.perf_counter()
    camera = sim.truth.camera
    solution = solve_stars(found.x, found.y, flux=found.flux, **image_solver_kwargs(params, camera))
    inside = sim.truth.inside()
    truth = tagged_truth(sim.truth, params.get("timing_error_s", 0.0))
    row = solution_columns(solution, truth, camera, tolerance_px, len(found))
    row.update(time_s=(t2 - t1) + solution.solve_time_s, time_render_s=t1 - t0, time_detect_s=t2 - t1,
               time_identify_s=solution.solve_time_s, n_truth=int(np.count_nonzero(inside)),
               centroid_rms_px=centroid_rms_px(found, sim.truth.x[inside], sim.truth.y[inside]))
    return TrialOutput(row, image=sim.image, truth=sim.truth)


def check(params: Mapping[str, Any]) -> None:
    check_solver(params)
    check_scene(params)
    if not params["distortion_known"] and not params["calibrated"]:
        raise SpecError("distortion_known = false needs calibrated = true (without it the solver knows only "
                        "the field of view, never the distortion)")


LEVEL = register(Level(
    name="image", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check, chunk_trials=10,
    columns={"time_render_s": pa.float64(), "time_detect_s": pa.float64(), "time_identify_s": pa.float64(),
             "n_truth": pa.int32(), "centroid_rms_px": pa.float64()}))
