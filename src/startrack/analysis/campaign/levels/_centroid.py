"""Level "centroid": an image of ``stars_per_image`` synthetic stars of one magnitude, detected
and centroided (Huffman 2006 §4.2.2, Table 4.2: weighted sum against maximum likelihood).

The stars sit one per cell of a ``grid_px`` grid (a random whole-pixel offset within a quarter
cell and a uniform sub-pixel phase; cells ``margin_px`` from the edges), so that none blend.
Each carries ``sensor.electrons(mag_v)`` electrons spread by the pixel-integrated Gaussian PSF of
the sensor's ``psf_sigma_px`` (:func:`startrack.simulate.render_gaussian_psf`), read out by
:func:`startrack.simulate.read_out` with the ``noise_*`` switches; the sensor is the ``sensor``
preset with any Optics / Detector field and the exposure set (the image level's parameters,
:mod:`._scene`). The image is detected by the ``StarDetector`` of the ``detect_*`` settings;
each true star takes its nearest detection within ``match_px``. The trial's attitude is not used.

Common columns (no identification): ``status`` "OK" when a star was found (else
"TOO_FEW_STARS"); ``correct`` = every star found and no other detection; ``n_stars`` the
detections, ``n_matched`` the true stars found; ``time_s`` the detection (the whole
``StarDetector.detect`` call: background, threshold, grouping, centroid); the true attitude NaN.
Extra columns: ``centroid_rms_axis_px``, the per-axis RMS centroid error of the found stars
(sqrt of the mean squared distance over 2), ``electrons_per_star``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ....simulate import read_out, render_gaussian_psf
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._measure import check_builds, match_truth, measurement_columns
from ._scene import (
    DETECT_PARAMS,
    FRAME_PARAMS,
    NOISE_PARAMS,
    SENSOR_FIELD_PARAMS,
    frame_detector,
    frame_noise,
    frame_sensor,
)

SENSOR_PARAMS = tuple(p for p in FRAME_PARAMS if p.name in ("sensor", "exposure_s"))
"""The sensor preset and exposure of the image level (the rest of its frame parameters describe
a camera and a sky this level does not have)."""

FIELD_PARAMS = (
    Param("mag_v", "float", 3.0, "V magnitude of every star", lo=-5.0, hi=20.0),
    Param("stars_per_image", "int", 30, "stars in the image (at most one per grid cell)", lo=1, hi=100000),
    Param("grid_px", "int", 200, "side of the grid cells, one star each (px)", lo=8, hi=10000),
    Param("margin_px", "int", 60, "the grid starts this far from the top-left edges (px)", lo=0, hi=10000),
    Param("width", "int", 1280, "image width (px)", lo=16, hi=20000),
    Param("height", "int", 1024, "image height (px)", lo=16, hi=20000),
    Param("match_px", "float", 3.0, "largest distance from a true star to its detection (px)", lo=0.1, hi=100.0),
)

PARAMS = params_by_name(FIELD_PARAMS, SENSOR_PARAMS, SENSOR_FIELD_PARAMS, NOISE_PARAMS,
                        DETECT_PARAMS)


def grid_cells(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Top-left corners (x, y) of the grid cells, row by row."""
    m, step = params["margin_px"], params["grid_px"]
    gy, gx = np.mgrid[m: params["height"] - m: step, m: params["width"] - m: step]
    return gx.ravel().astype(float), gy.ravel().astype(float)


def star_positions(params: Mapping[str, Any], rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """True positions (px) of the image's stars, the first ``stars_per_image`` cells."""
    gx, gy = grid_cells(params)
    n, jitter = params["stars_per_image"], params["grid_px"] // 4
    x = gx + rng.integers(0, jitter + 1, gx.size) + rng.uniform(-0.5, 0.5, gx.size)
    y = gy + rng.integers(0, jitter + 1, gy.size) + rng.uniform(-0.5, 0.5, gy.size)
    return x[:n], y[:n]


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """Render, detect and centroid one image (``rot`` and ``tolerance_px`` are not used)."""
    sensor = frame_sensor(params)
    x, y = star_positions(params, rng)
    flux = float(sensor.electrons(params["mag_v"]))
    signal = render_gaussian_psf((params["height"], params["width"]), x, y, np.full(x.size, flux),
                                 sensor.psf_sigma_px)
    image = read_out(signal, sensor, noise=frame_noise(params), rng=rng)
    detector = frame_detector(params)
    t0 = time.perf_counter()
    found = detector.detect(image)
    time_s = time.perf_counter() - t0
    index = match_truth(x, y, found.x, found.y, params["match_px"])
    ok = index >= 0
    d2 = (found.x[index[ok]] - x[ok]) ** 2 + (found.y[index[ok]] - y[ok]) ** 2
    n_found = int(ok.sum())
    row = measurement_columns(status="OK" if n_found else "TOO_FEW_STARS",
                              correct=n_found == x.size and len(found) == n_found, n_stars=len(found),
                              n_matched=n_found, time_s=time_s)
    row.update(centroid_rms_axis_px=math.sqrt(float(d2.mean()) / 2.0) if n_found else math.nan,
               electrons_per_star=flux)
    return TrialOutput(row, image=image)


def check(params: Mapping[str, Any]) -> None:
    """Refuse more stars than grid cells, and settings the sensor, noise model or detector refuse."""
    cells = grid_cells(params)[0].size
    if params["stars_per_image"] > cells:
        raise SpecError(f"stars_per_image ({params['stars_per_image']}) exceeds the {cells} cells of a "
                        f"{params['grid_px']} px grid in {params['width']} x {params['height']} px "
                        f"(margin {params['margin_px']} px)")
    check_builds(params, frame_sensor, frame_noise, frame_detector)


LEVEL = register(Level(
    name="centroid", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns={"centroid_rms_axis_px": pa.float64(), "electrons_per_star": pa.float64()}, chunk_trials=5))
