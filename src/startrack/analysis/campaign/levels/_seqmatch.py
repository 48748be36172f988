"""Level "seqmatch": the attitude of every frame of a slow sequence by one matching method, and
the time the whole chain takes (Huffman 2006 §7.2-7.4, Table 8.2).

The sequence: ``n_frames`` frames at ``frame_rate_hz`` (:func:`startrack.simulate.simulate_sequence`,
the image level's simulator settings), the camera turning at ``turn_rate_deg_s`` about a random
axis (drawn from the trial's stream), frame 0's mid-exposure at the trial's attitude. Each frame
is detected (``detect_*``), then, by ``match_method``:

- ``triangle``: frame 0 solved lost-in-space (``quads``), then the relative attitude of each
  pair of consecutive frames by :func:`startrack.track._relative.triangle_match`, chained;
- ``rate``: frames 0 and 1 solved lost-in-space, the rate from their attitudes
  (:func:`startrack.rate.rate_between`), then :func:`startrack.track._relative.rate_match`,
  chained;
- any lost-in-space matcher (``nvertex-3``, ``nvertex-4``, ``nvertex-5``, ``quads``, ...):
  ``solve_stars(..., camera=..., method=...)`` on every frame (absolute, not chained).

The solver is given the true camera, as the seed knew its own. Relative matches accept pairs
within 3 pixel angles. The common columns describe the **last frame** (the chained or solved
attitude against its truth; a chained frame has no covariance nor false-match bound: NaN sigmas,
bound 1, and ``n_matched`` is the stars paired with the previous frame); ``time_s`` is the
whole chain, detection included (the seed timed threshold, centroid, match and QUEST). Extra
columns: ``frames_solved``, ``frames_correct``, ``last_error_px`` and ``max_error_px`` (total
attitude error over the pixel angle, last frame and worst frame), ``time_render_s``.
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
from ....errors import require
from ....frames import attitude_error
from ....identify import MATCHERS, check_method
from ....rate import rate_between
from ....results import AttitudeSolution, Detections, Status
from ....simulate import ConstantRate, simulate_sequence
from ....solve import solve_stars
from ....track import rate_match, triangle_match
from ....units import DEG
from .._outcome import error_columns, solution_columns
from .._params import Param, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS
from ._scene import (
    DETECT_PARAMS,
    FRAME_PARAMS,
    NOISE_PARAMS,
    SENSOR_FIELD_PARAMS,
    check_scene,
    frame_camera,
    frame_detector,
    frame_noise,
    frame_sensor,
    frame_sky,
)
from ._sequence import SEQUENCE_PARAMS

RELATIVE = ("triangle", "rate")
TOLERANCE_PX = 3.0
"""Relative matches pair stars within this many pixel angles."""

MATCH_PARAMS = (
    Param("match_method", "str", "triangle", "how each frame gets its attitude (module docstring)",
          choices=(*RELATIVE, *(name for name in MATCHERS if name != "overlay"))),
    Param("turn_rate_deg_s", "float", 0.2, "the camera's rate about a random axis (deg/s)", lo=0.0, hi=100.0),
    Param("epoch_jyear", "float", 2025.0, "epoch of the star positions, scene and solver (Julian year, TDB)",
          lo=1900.0, hi=2100.0),
)
PARAMS = params_by_name(CAMERA_PARAMS, tuple(p for p in FRAME_PARAMS if p.name not in ("rate_deg_s", "calibrated")),
                        SENSOR_FIELD_PARAMS, NOISE_PARAMS, DETECT_PARAMS, SEQUENCE_PARAMS, MATCH_PARAMS)


def render_sequence(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator):
    """The camera and the frames of a trial (list of SimulatedImage)."""
    camera = frame_camera(params)
    axis = rng.normal(size=3)
    rate = axis / np.linalg.norm(axis) * params["turn_rate_deg_s"] * DEG
    sensor = frame_sensor(params)
    frames = simulate_sequence(
        camera, ConstantRate(rot, rate), params["n_frames"], frame_rate_hz=params["frame_rate_hz"],
        start_s=-0.5 * sensor.exposure_s, sensor=sensor, max_mag=params["max_mag"],
        catalog_epoch_jyear=params["epoch_jyear"], noise=frame_noise(params), seed=int(rng.integers(2**63)),
        line_time_s=params["line_time_s"], sky_background=frame_sky(params))
    return camera, list(frames)


def _solve(found: Detections, camera: Camera, method: str, epoch: float) -> AttitudeSolution:
    return solve_stars(found.x, found.y, flux=found.flux, camera=camera, method=check_method(method), epoch=epoch)


def absolute_chain(found: list[Detections], camera: Camera, method: str, epoch: float) -> list[AttitudeSolution]:
    """Every frame solved lost-in-space by ``method``."""
    return [_solve(f, camera, method, epoch) for f in found]


def relative_chain(found: list[Detections], camera: Camera, method: str, dt_s: float,
                   epoch: float) -> tuple[list[AttitudeSolution], int]:
    """Frame 0 (and 1 for ``rate``) solved lost-in-space, the rest chained by relative matches.

    Returns the solutions (a chained frame's has the relative match's status and the chained
    attitude) and the stars the last relative match paired (-1 when the last frame was solved
    lost-in-space)."""
    tol = TOLERANCE_PX / math.sqrt(camera.fx * camera.fy)
    out, pairs, rate = [_solve(found[0], camera, "quads", epoch)], -1, None
    for k in range(1, len(found)):
        pairs = 0
        if not out[-1].solved:
            out.append(AttitudeSolution(status=Status.NO_MATCH, reason=f"the chain broke before frame {k}"))
            continue
        if method == "rate" and rate is None:
            out.append(_solve(found[k], camera, "quads", epoch))
            rate = rate_between(out[-2].rot_cam_from_icrs, out[-1].rot_cam_from_icrs, dt_s) if out[-1].solved else None
            pairs = -1
            continue
        prev, cur = (camera.pixel_to_vector(f.x, f.y) for f in (found[k - 1], found[k]))
        rel = (rate_match(prev, cur, require(rate, "the rate"), dt_s, tol) if method == "rate"
               else triangle_match(prev, cur, tol))
        rot = None if rel.rot_cam2_from_cam1 is None else rel.rot_cam2_from_cam1 * out[-1].rot_cam_from_icrs
        out.append(AttitudeSolution(status=rel.status if rot is not None else Status.NO_MATCH, reason=rel.reason,
                                    rot_cam_from_icrs=rot))
        pairs = int(rel.index1.size) if rot is not None else 0
    return out, pairs


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """Render a sequence, then time detection and matching of all its frames."""
    t0 = time.perf_counter()
    camera, frames = render_sequence(params, rot, rng)
    t1 = time.perf_counter()
    detector, method, epoch = frame_detector(params), params["match_method"], params["epoch_jyear"]
    found = [detector.detect(sim.image) for sim in frames]
    pairs = -1
    if method in RELATIVE:
        solutions, pairs = relative_chain(found, camera, method, 1.0 / params["frame_rate_hz"], epoch)
    else:
        solutions = absolute_chain(found, camera, method, epoch)
    t2 = time.perf_counter()
    truths = [sim.truth.rot_cam_from_icrs for sim in frames]
    pixel = 1.0 / math.sqrt(camera.fx * camera.fy)
    errors = np.array([attitude_error(t, s.rot_cam_from_icrs) / pixel if s.solved else np.nan
                       for t, s in zip(truths, solutions, strict=True)])
    correct = sum(bool(error_columns(t, s.rot_cam_from_icrs, camera, tolerance_px)["correct"])
                  for t, s in zip(truths, solutions, strict=True) if s.solved)
    last = solutions[-1]
    row = solution_columns(last, truths[-1], camera, tolerance_px, len(found[-1]))
    if pairs >= 0:  # chained: the stars paired with the previous frame
        row["n_matched"] = pairs
    row.update(time_s=t2 - t1, time_render_s=t1 - t0, frames_solved=int(np.isfinite(errors).sum()),
               frames_correct=int(correct), last_error_px=float(errors[-1]),
               max_error_px=float(np.nanmax(errors)) if np.isfinite(errors).any() else math.nan)
    return TrialOutput(row, image=frames[-1].image, truth=frames[-1].truth)


def check(params: Mapping[str, Any]) -> None:
    """The image level's scene checks (camera, sensor, noise, detector)."""
    check_scene(params)


LEVEL = register(Level(
    name="seqmatch", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns={"frames_solved": pa.int32(), "frames_correct": pa.int32(), "last_error_px": pa.float64(),
             "max_error_px": pa.float64(), "time_render_s": pa.float64()}, chunk_trials=1))
