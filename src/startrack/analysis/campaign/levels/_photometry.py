"""Level "photometry": the magnitude error of thresholded weighted-sum photometry (Huffman 2006 §5.3,
Tables 5.2 and 5.3).

Each trial renders ``stars_per_image`` stars of magnitude ``mag_v`` at uniformly random
positions (at least ``margin_px`` from the edges) of the ``camera`` preset's image, at the
trial's attitude, through :func:`startrack.simulate.render_stars` with the sensor (the
``sensor`` preset, ``aperture_area_m2`` and any Optics / Detector field, as at the image level)
and the ``noise_*`` switches. The seed's photometry follows: subtract the mean bias and dark,
keep the pixels above ``threshold_sigma`` times the dark + read noise
(``sqrt(dark_e + read_noise_e^2)``), group them 8-connected, and take each star's cluster sum
as its signal, :func:`startrack.simulate.magnitude_from_electrons` as its magnitude. A star not
above the threshold, or sharing its cluster with another (the seed's centroider would return
one star for two), is not measured. The seed kept only the frames in which all 20 stars were
measured: a trial whose stars are not all measured has status "TOO_FEW_STARS" and no error.
The trial's error is that of its first star (all are alike), so that the mean and the standard
deviation over the trials are those over stars, the seed's statistics.

Common columns (no identification): ``status`` "OK" (every star measured) or
"TOO_FEW_STARS"; ``correct`` as ``solved``; ``n_stars`` and ``n_matched`` the stars measured;
``time_s`` the photometry's time; the true attitude. Extra columns: ``mag_err_v`` (measured
minus true V of the first star; NaN unless "OK"), ``frame_mag_err_v`` (the mean over the
frame's measured stars).
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from scipy import ndimage
from scipy.spatial.transform import Rotation

from ....camera import PRESETS, get_preset
from ....simulate import Sensor, magnitude_from_electrons, render_stars
from .._params import Param, params_by_name
from . import Level, TrialOutput, register
from ._centroid import SENSOR_PARAMS
from ._measure import check_builds, measurement_columns
from ._scene import NOISE_PARAMS, SENSOR_FIELD_PARAMS, frame_noise, frame_sensor

FIELD_PARAMS = (
    Param("camera", "str", "far-mst", "the camera preset whose image the stars are placed in",
          choices=tuple(sorted(PRESETS))),
    Param("mag_v", "float", 2.0, "V magnitude of every star", lo=-5.0, hi=20.0),
    Param("stars_per_image", "int", 20, "stars in the image", lo=1, hi=100000),
    Param("margin_px", "float", 20.0, "stars are at least this far from the edges (px)", lo=0.0, hi=10000.0),
    Param("threshold_sigma", "float", 5.0, "threshold in units of the dark + read noise", lo=0.0, hi=1000.0),
)

PARAMS = params_by_name(FIELD_PARAMS, SENSOR_PARAMS, SENSOR_FIELD_PARAMS, NOISE_PARAMS)


def threshold_adu(sensor: Sensor, k_sigma: float) -> float:
    """``k_sigma`` times the dark + read noise of a pixel, in ADU above the mean bias and dark."""
    det = sensor.detector
    return k_sigma * math.sqrt(sensor.dark_e + det.read_noise_e**2) / det.gain_e_per_adu


def weighted_sum_mags(image: NDArray, x: NDArray, y: NDArray, sensor: Sensor, k_sigma: float) -> NDArray[np.float64]:
    """Magnitude of each true star (at ``x``, ``y``, px) from the sum of its above-threshold
    8-connected cluster; NaN when it is not detected or shares its cluster (module docstring)."""
    det = sensor.detector
    signal = image.astype(float) - (det.bias_adu + sensor.dark_e / det.gain_e_per_adu)
    labels, n = ndimage.label(signal > threshold_adu(sensor, k_sigma), structure=np.ones((3, 3)))
    sums = ndimage.sum_labels(signal, labels, index=np.arange(n + 1))
    rows = np.clip(np.round(y).astype(int), 0, labels.shape[0] - 1)
    cols = np.clip(np.round(x).astype(int), 0, labels.shape[1] - 1)
    lab = labels[rows, cols]
    shared = np.bincount(lab, minlength=n + 1)[lab] > 1
    electrons = np.where((lab > 0) & ~shared, sums[lab] * det.gain_e_per_adu, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(electrons > 0, magnitude_from_electrons(electrons, sensor), np.nan)


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One frame of equal stars, measured (``tolerance_px`` is not used)."""
    camera, sensor = get_preset(params["camera"]), frame_sensor(params)
    n, m = params["stars_per_image"], params["margin_px"]
    x, y = rng.uniform(m, camera.width - m, n), rng.uniform(m, camera.height - m, n)
    mag = params["mag_v"]
    sim = render_stars(camera, rot, rot.inv().apply(camera.pixel_to_vector(x, y)), np.full(n, mag), np.arange(n),
                       sensor=sensor, rng=rng, noise=frame_noise(params))
    t0 = time.perf_counter()
    order = np.argsort(sim.truth.ids)  # the truth in the order the stars were given
    est = weighted_sum_mags(sim.image, sim.truth.x[order], sim.truth.y[order], sensor, params["threshold_sigma"])
    time_s = time.perf_counter() - t0
    measured = int(np.isfinite(est).sum())
    ok = measured == n and len(sim.truth) == n
    row = measurement_columns(status="OK" if ok else "TOO_FEW_STARS", correct=ok, n_stars=measured,
                              n_matched=measured, time_s=time_s, rot_cam_from_icrs=rot)
    row.update(mag_err_v=float(est[0] - mag) if ok else math.nan,
               frame_mag_err_v=float(np.nanmean(est - mag)) if measured else math.nan)
    return TrialOutput(row, image=sim.image, truth=sim.truth)


def check(params: Mapping[str, Any]) -> None:
    """Refuse settings the sensor or noise model refuse."""
    check_builds(params, frame_sensor, frame_noise)


LEVEL = register(Level(
    name="photometry", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns={"mag_err_v": pa.float64(), "frame_mag_err_v": pa.float64()}, chunk_trials=10))
