"""Level "image": render a frame of the Hipparcos sky (:func:`startrack.simulate.simulate_frame`),
detect its stars (:class:`startrack.detect.StarDetector`) and solve them lost-in-space.

Every simulator and detector setting is a parameter (:mod:`.scene`). The solver gets the true
camera when ``calibrated``, else the FOV (``fov_known``) or the FOV range. The attitude is judged
at mid-exposure (the frame's time tag). Extra columns: the per-stage times ``time_render_s``,
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

from ....results import Detections
from ....simulate import FrameTiming, simulate_frame
from ....solve import solve_stars
from ..outcome import solution_columns
from ..params import params_by_name
from . import Level, TrialOutput, register
from .common import CAMERA_PARAMS, SOLVER_PARAMS, check_solver
from .scene import (
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
)

PARAMS = params_by_name(CAMERA_PARAMS, FRAME_PARAMS, SENSOR_FIELD_PARAMS, NOISE_PARAMS, DETECT_PARAMS,
                        SOLVER_PARAMS)
MATCH_PX = 2.0
"""Largest distance (px) at which a detection counts as the centroid of a true star."""


def image_solver_kwargs(params: Mapping[str, Any], camera) -> dict[str, Any]:
    """The solver's knowledge of the camera: all of it, its FOV, or a FOV range."""
    if params["calibrated"]:
        knowledge = {"camera": camera}
    elif params["fov_known"]:
        knowledge = {"fov_deg": camera.fov_deg, "width": camera.width, "height": camera.height}
    else:
        knowledge = {"fov_range_deg": tuple(params["fov_range_deg"]), "width": camera.width, "height": camera.height}
    return {**knowledge, "method": params["method"], "epoch": params["epoch_jyear"]}


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
                          sky_background=frame_sky(params))


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """Render, detect and solve one frame at ``rot`` (mid-exposure ``rot_cam_from_icrs``)."""
    t0 = time.perf_counter()
    sim = render(params, rot, rng)
    t1 = time.perf_counter()
    found = frame_detector(params).detect(sim.image)
    t2 = time.perf_counter()
    camera = sim.truth.camera
    solution = solve_stars(found.x, found.y, flux=found.flux, **image_solver_kwargs(params, camera))
    inside = sim.truth.inside()
    row = solution_columns(solution, sim.truth.rot_cam_from_icrs, camera, tolerance_px, len(found))
    row.update(time_s=(t2 - t1) + solution.solve_time_s, time_render_s=t1 - t0, time_detect_s=t2 - t1,
               time_identify_s=solution.solve_time_s, n_truth=int(np.count_nonzero(inside)),
               centroid_rms_px=centroid_rms_px(found, sim.truth.x[inside], sim.truth.y[inside]))
    return TrialOutput(row, image=sim.image, truth=sim.truth)


def check(params: Mapping[str, Any]) -> None:
    check_solver(params)
    check_scene(params)


LEVEL = register(Level(
    name="image", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check, chunk_trials=10,
    columns={"time_render_s": pa.float64(), "time_detect_s": pa.float64(), "time_identify_s": pa.float64(),
             "n_truth": pa.int32(), "centroid_rms_px": pa.float64()}))
