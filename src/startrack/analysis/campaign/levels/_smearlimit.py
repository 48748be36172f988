"""Level "smearlimit": the largest rate at which a star smears by at most a tenth of a pixel in
one exposure, and the smear the simulator then renders (Samaan 2002 "Maximum Angular Rate
Estimation", Table 1).

The rate is :func:`startrack.simulate.max_rate_rad_s`: ``smear_fraction_px`` pixel angles
(``ifov = "center"``: 1 / fx, the pixel at the principal point; ``"mean"``: FOV / width) per
``exposure_s``. Each trial then renders the Hipparcos sky to ``max_mag`` at the trial's
attitude (mid-exposure) with the camera turning at that rate about a random axis across the
boresight (:func:`startrack.simulate.simulate_frame`, the ``sensor`` preset with the exposure)
and measures from the simulator's truth how far each star centred in the image moved from the
start to the end of the exposure: ``smear_px`` (median over the stars) and ``smear_max_px``.
A pinhole stretches motion off axis (by 1 / cos^2 of the off-axis angle along the radius), so
stars away from the centre move slightly more than the target.

Common columns (no identification): ``status`` "OK" when a star is in the image (else
"TOO_FEW_STARS"); ``correct`` = every star's smear within 2 % of ``smear_fraction_px`` (the
rate is negligible over the whole image, not only at its centre); ``n_stars`` the stars in the
image, ``n_matched`` 0; ``time_s`` the rendering; the true attitude. Extra columns:
``max_rate_deg_s``, ``smear_px``, ``smear_max_px``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....camera import PRESETS, Camera, get_preset
from ....simulate import SENSOR_PRESETS, get_sensor_preset, max_rate_rad_s, simulate_frame
from ....units import DEG
from .._params import Param, params_by_name
from . import Level, TrialOutput, register
from ._common import CAMERA_PARAMS
from ._measure import check_builds, measurement_columns

CORRECT_MARGIN = 0.02
"""``correct``: the largest smear is within this fraction of ``smear_fraction_px``."""

SMEAR_PARAMS = (
    Param("camera", "str", "starnav-i", 'a camera preset ("": a pinhole camera from fov_deg, width, height)',
          choices=("", *sorted(PRESETS))),
    Param("exposure_s", "float", 0.01, "exposure (integration) time (s)", lo=1e-6, hi=3600.0),
    Param("smear_fraction_px", "float", 0.1, "smear that counts as negligible (px)", lo=1e-4, hi=100.0),
    Param("ifov", "str", "center", "the pixel angle: 1 / fx (center) or FOV / width (mean)",
          choices=("center", "mean")),
    Param("sensor", "str", "generic-cmos", "the sensor preset of the rendered check",
          choices=tuple(sorted(SENSOR_PRESETS))),
    Param("max_mag", "float", 7.0, "faintest catalog star rendered (V)", lo=-2.0, hi=16.0),
)

PARAMS = params_by_name(CAMERA_PARAMS, SMEAR_PARAMS)


def smear_camera(params: Mapping[str, Any]) -> Camera:
    """The camera preset, or a pinhole of ``fov_deg`` across ``width`` x ``height``."""
    if params["camera"]:
        return get_preset(params["camera"])
    return Camera.from_fov(params["width"], params["height"], params["fov_deg"], name="pinhole")


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """The smear-limited rate, and one frame rendered at it (``tolerance_px`` is not used)."""
    camera = smear_camera(params)
    rate = max_rate_rad_s(camera, params["exposure_s"], params["smear_fraction_px"], params["ifov"])
    phi = rng.uniform(0.0, 2.0 * math.pi)
    sensor = get_sensor_preset(params["sensor"]).with_exposure(params["exposure_s"])
    t0 = time.perf_counter()
    sim = simulate_frame(camera, rot, max_mag=params["max_mag"], sensor=sensor, rng=rng,
                         rate_rad_s=rate * np.array([math.cos(phi), math.sin(phi), 0.0]))
    time_s = time.perf_counter() - t0
    smear = sim.truth.streak_length_px[sim.truth.inside()]
    n = int(smear.size)
    limit = params["smear_fraction_px"] * (1.0 + CORRECT_MARGIN)
    row = measurement_columns(status="OK" if n else "TOO_FEW_STARS", correct=bool(n) and bool(smear.max() <= limit),
                              n_stars=n, n_matched=0, time_s=time_s, rot_cam_from_icrs=rot)
    row.update(max_rate_deg_s=rate / DEG, smear_px=float(np.median(smear)) if n else math.nan,
               smear_max_px=float(smear.max()) if n else math.nan)
    return TrialOutput(row, image=sim.image, truth=sim.truth)


def check(params: Mapping[str, Any]) -> None:
    """Build the camera once, so that a pinhole it refuses is reported before any work."""
    check_builds(params, smear_camera)


LEVEL = register(Level(
    name="smearlimit", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns={"max_rate_deg_s": pa.float64(), "smear_px": pa.float64(), "smear_max_px": pa.float64()},
    chunk_trials=20))
