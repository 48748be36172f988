"""Level "sequence": a simulated sequence of frames (:func:`startrack.simulate.simulate_sequence`)
through the :class:`startrack.track.Tracker`, the camera turning at a constant rate.

The trial's attitude is the attitude of the first frame's mid-exposure; ``rate_deg_s`` is the
constant camera-frame rate, ``n_frames`` frames at ``frame_rate_hz``. Each frame is detected
(``detect_*`` settings) and handed to the Tracker (``tracker_*`` settings, the fields of
:class:`startrack.track.TrackerOptions`), which solves lost-in-space until it has an attitude and
tracks after that. The common columns describe the **last frame** (the steady state); the
level's own columns describe the whole sequence: ``frames_solved``, ``frames_correct``,
``frames_tracked`` (attitudes from tracking, not lost-in-space), ``acquire_frame`` (the first
correct frame, -1 if none), ``err_rms_arcsec`` (RMS total error over the correct frames),
``rate_err_deg_s`` (the last frame's rate error, NaN without a rate), ``time_lis_s`` and
``time_track_s`` (median step time of the lost-in-space and the tracking steps). The Tracker
reports no covariance nor false-match bound: the last frame's ``sigma_*`` are NaN and its
``false_match_prob`` is 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....errors import require
from ....results import AttitudeSolution
from ....simulate import ConstantRate, simulate_sequence
from ....track import TRACKING, Tracker, TrackerOptions
from ....units import DEG
from .._outcome import error_columns, solution_columns
from .._params import Param, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS, SOLVER_PARAMS, check_solver
from ._scene import (
    DETECT_PARAMS,
    FRAME_PARAMS,
    NOISE_PARAMS,
    SENSOR_FIELD_PARAMS,
    check_scene,
    dataclass_params,
    frame_camera,
    frame_detector,
    frame_noise,
    frame_sensor,
    frame_sky,
)

SEQUENCE_PARAMS = (
    Param("n_frames", "int", 20, "frames in the sequence", lo=2, hi=100000),
    Param("frame_rate_hz", "float", 5.0, "frames per second (the exposure must fit in a frame period)",
          lo=1e-3, hi=10000.0),
)
TRACKER_PARAMS = dataclass_params(TrackerOptions, "tracker_", "TrackerOptions", auto=False)
RENDERED_ELSEWHERE = ("aberration_annual", "aberration_velocity_km_s")
"""Frame parameters the sequence simulator does not render (the image level does)."""
PARAMS = params_by_name(CAMERA_PARAMS, tuple(p for p in FRAME_PARAMS if p.name not in RENDERED_ELSEWHERE),
                        SENSOR_FIELD_PARAMS, NOISE_PARAMS, DETECT_PARAMS,
                        SEQUENCE_PARAMS, TRACKER_PARAMS,
                        tuple(p for p in SOLVER_PARAMS if p.name != "method"))


def make_tracker(params: Mapping[str, Any], camera) -> Tracker:
    """The Tracker of a trial, told what the solver of the image level would be told."""
    options = TrackerOptions(**{k[8:]: v for k, v in params.items() if k.startswith("tracker_")})
    knowledge: dict[str, Any] = {"width": camera.width, "height": camera.height}
    if params["calibrated"]:
        knowledge = {"camera": camera}
    elif params["fov_known"]:
        knowledge["fov_deg"] = camera.fov_deg
    else:
        knowledge["fov_range_deg"] = tuple(params["fov_range_deg"])
    return Tracker(**knowledge, epoch=params["epoch_jyear"], options=options)


def _frames(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator):
    camera = frame_camera(params)
    profile = ConstantRate(rot, np.radians(np.asarray(params["rate_deg_s"], dtype=float)))
    sensor = frame_sensor(params)
    start = -0.5 * sensor.exposure_s  # frame 0's mid-exposure is the trial's attitude
    return camera, simulate_sequence(
        camera, profile, params["n_frames"], frame_rate_hz=params["frame_rate_hz"], start_s=start, sensor=sensor,
        max_mag=params["max_mag"], catalog_epoch_jyear=params["epoch_jyear"], noise=frame_noise(params),
        seed=int(rng.integers(2**63)), line_time_s=params["line_time_s"], sky_background=frame_sky(params))


def _median(values: list[float]) -> float:
    return float(np.median(values)) if values else float("nan")


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """Track one simulated sequence (see the module docstring)."""
    camera, frames = _frames(params, rot, rng)
    tracker, detector = make_tracker(params, camera), frame_detector(params)
    errors: list[float] = []
    times: dict[str, list[float]] = {"lis": [], "track": []}
    solved = correct = tracked = 0
    acquire, last, n_stars = -1, None, 0
    for k, sim in enumerate(frames):
        found = detector.detect(sim.image)
        step = tracker.update(found.x, found.y, sim.truth.t_mid_s, flux=found.flux)
        times["track" if step.mode == TRACKING else "lis"].append(step.time_s)
        last, n_stars = (sim, step), len(found)
        if step.rot_cam_from_icrs is None:
            continue
        solved += 1
        tracked += step.mode == TRACKING
        judged = error_columns(sim.truth.rot_cam_from_icrs, step.rot_cam_from_icrs, camera, tolerance_px)
        if judged["correct"]:
            correct += 1
            acquire = k if acquire < 0 else acquire
            errors.append(judged["err_total_arcsec"])
    sim, step = require(last, "the last frame of the sequence")
    row = solution_columns(_as_solution(step), sim.truth.rot_cam_from_icrs, camera, tolerance_px, n_stars)
    row.update(frames_solved=solved, frames_correct=correct, frames_tracked=tracked, acquire_frame=acquire,
               err_rms_arcsec=float(np.sqrt(np.mean(np.square(errors)))) if errors else float("nan"),
               rate_err_deg_s=_rate_error(step, sim), time_lis_s=_median(times["lis"]),
               time_track_s=_median(times["track"]), n_matched=step.n_matched)
    return TrialOutput(row, image=sim.image, truth=sim.truth)


def _as_solution(step) -> AttitudeSolution:
    """A TrackStep as the AttitudeSolution the common columns read (the Tracker gives no
    covariance nor false-match bound: NaN sigmas, bound 1)."""
    return AttitudeSolution(status=step.status, reason=step.reason, rot_cam_from_icrs=step.rot_cam_from_icrs,
                            solve_time_s=step.time_s)


def _rate_error(step, sim) -> float:
    if step.rate_rad_s is None:
        return float("nan")
    return float(np.linalg.norm(np.asarray(step.rate_rad_s) - sim.truth.rate_cam_rad_s) / DEG)


def check(params: Mapping[str, Any]) -> None:
    check_solver(params)
    check_scene(params)
    TrackerOptions(**{k[8:]: v for k, v in params.items() if k.startswith("tracker_")})


LEVEL = register(Level(
    name="sequence", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    chunk_trials=1, columns={"frames_solved": pa.int32(), "frames_correct": pa.int32(), "frames_tracked": pa.int32(),
                             "acquire_frame": pa.int32(), "err_rms_arcsec": pa.float64(),
                             "rate_err_deg_s": pa.float64(), "time_lis_s": pa.float64(),
                             "time_track_s": pa.float64()}))
