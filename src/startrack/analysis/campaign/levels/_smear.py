"""Level "smear": one smeared point-star image, first-moment centroids, and the two centroid-error
metrics of Samaan 2002 (Samaan et al. 2002, Table 2: the interstar-angle sigma, eq. 7, and the
image-plane STD, eq. 8, in microradians).

The camera is StarNav I as Table 1 implies it (512 x 512 px, 8 deg field: IFOV 0.015625 deg =
272.7 urad; the text says 7 deg, Samaan 2002 Table 1). ``stars`` stars are placed where
their path stays ``margin_px`` inside the image and rendered from the trial's attitude while the
camera turns at ``rate_deg_s`` about a uniformly random axis for ``exposure_s``; each keeps its
electrons (uniform in ``star_electrons``) whatever the smear, as the seed's rule says ("the
volume is constant, the area grows"). The seed gives no noise model: the defaults (1e3-4e3 e-,
sky 10 e-, read noise 10 e-, PSF sigma 1 px) put the unsmeared errors near its 35.6 / 39.1 urad.
The image is segmented (:func:`startrack.rate._streak_detect.find_streaks`, ``min_area_px``) and
each blob's intensity centroid is the measurement (``centroider = "moments"``, the seed's first
moments), or the stars are found and centroided by :class:`startrack.detect.StarDetector` with the
``centroider`` named (e.g. ``"mle"``, the maximum-likelihood pixel-integrated Gaussian fit);
each true star (its mid-exposure position, the time tag of Samaan 2002 eq. 6) takes its nearest
centroid within ``match_px``, and stars with another star within ``crowd_px`` are left out (a
blend is not a centroid error).

- ``sigma_urad``: this image's RMS over its star pairs of measured minus true interstar angle
  (eq. 7 of one image; ``rms:sigma_urad`` over a cell is eq. 7 with every image weighted alike);
- ``std_urad``: this image's RMS image-plane residual, sqrt(mean(dx^2 + dy^2)) / f, of the
  centroids against the positions predicted with the best attitude estimate (QUEST on the
  matched stars), eq. 8 (``rms:std_urad``: sqrt(STD_x^2 + STD_y^2) / f when the residuals have
  zero mean, which the attitude fit ensures);
- ``std_truth_urad``: the same against the true mid-exposure positions (no attitude fit).

Common columns: ``status`` "OK" when three or more stars are matched (else TOO_FEW_STARS); the
attitude errors are those of the fitted mid-exposure attitude (``correct`` within the campaign's
tolerance); ``n_stars`` the blobs found, ``n_matched`` the stars scored; ``false_match_prob`` NaN;
``time_s`` the segmentation and centroiding. Extra columns: the three metrics, ``smear_px`` (the
largest path length of a star over the exposure) and ``n_crowded`` (stars left out as blends).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ....attitude import solve_wahba
from ....camera import Camera
from ....detect import CENTROIDERS, StarDetector
from ....errors import require
from ....rate import find_streaks
from ....units import DEG
from ..._streak_scenes import StreakScene, render_streak_scene, star_field, star_paths
from .._outcome import NAN, error_columns, truth_columns
from .._params import Param, params_by_name
from . import Level, TrialOutput, register
from ._measure import match_truth
from ._streaks import camera_params, check_range

SMEAR_PARAMS = (
    Param("exposure_s", "float", 0.01, "integration time t_s (s)", lo=1e-4, hi=10.0),
    Param("rate_deg_s", "float", 0.1, "the camera's rate about a random axis (deg/s); 0: no smear",
          lo=0.0, hi=100.0),
    Param("stars", "int", 8, "stars in the image (seed: about 8 per frame)", lo=2, hi=1000),
    Param("star_electrons", "floats", (1e3, 4e3), "stars' signal, uniform in [lo, hi] (e-)", lo=1.0, hi=1e12,
          length=2),
    Param("psf_sigma_px", "float", 1.0, "Gaussian PSF sigma (px)", lo=0.3, hi=10.0),
    Param("sky_e", "float", 10.0, "flat sky per pixel over the exposure (e-)", lo=0.0, hi=1e6),
    Param("read_noise_e", "float", 10.0, "read noise per pixel, 1-sigma (e-)", lo=0.0, hi=1e4),
    Param("margin_px", "float", 10.0, "every star path stays this far inside the image (px)", lo=0.0, hi=1000.0),
    Param("min_area_px", "int", 4, "smallest blob kept by the segmentation (px)", lo=1, hi=10000),
    Param("match_px", "float", 3.0, "largest distance from a true star to its centroid (px)", lo=0.1, hi=100.0),
    Param("crowd_px", "float", 8.0, "stars with another star this close are left out (px)", lo=0.0, hi=1000.0),
    Param("centroider", "str", "moments", '"moments": the intensity centroid of each segmented blob (the '
          "seed's first moments); otherwise a startrack.detect centroider of StarDetector (e.g. \"mle\")",
          choices=("moments", *CENTROIDERS)),
)
PARAMS = params_by_name(camera_params(fov_deg=8.0, width=512, height=512), SMEAR_PARAMS)


def random_axis(rng: np.random.Generator) -> NDArray[np.float64]:
    """A unit vector uniform on the sphere."""
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def draw_image(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator) -> StreakScene:
    """The smeared image of a trial (module docstring), starting at ``rot``."""
    camera = Camera.from_fov(params["width"], params["height"], fov_deg=params["fov_deg"])
    omega = params["rate_deg_s"] * DEG * random_axis(rng)
    exposure, n = params["exposure_s"], params["stars"]
    vectors = star_field(camera, omega, exposure, n, rng, margin_px=params["margin_px"])
    low, high = params["star_electrons"]
    return render_streak_scene(camera, rot, omega, exposure, vectors, rng.uniform(low, high, n),
                               psf_sigma_px=params["psf_sigma_px"], background_e=params["sky_e"],
                               read_noise_e=params["read_noise_e"], rng=rng)


def _angles(u: NDArray, v: NDArray) -> NDArray[np.float64]:
    return np.arctan2(np.linalg.norm(np.cross(u, v), axis=1), np.sum(u * v, axis=1))


def interstar_rms_rad(measured: NDArray, true: NDArray) -> float:
    """RMS over all pairs of the measured minus the true angle between unit vectors (N, 3) each."""
    i, j = np.triu_indices(len(measured), 1)
    return float(np.sqrt(np.mean((_angles(measured[i], measured[j]) - _angles(true[i], true[j])) ** 2)))


def image_rms_rad(camera: Camera, found_xy: NDArray, predicted_cam: NDArray) -> float:
    """sqrt(mean(dx^2 + dy^2)) / f of centroids (N, 2) against camera vectors (N, 3) projected."""
    x, y = camera.vector_to_pixel(predicted_cam)
    return float(np.sqrt(np.mean((found_xy[:, 0] - x) ** 2 + (found_xy[:, 1] - y) ** 2)) / camera.fx)


def matched(params: Mapping[str, Any], scene: StreakScene, found_xy: NDArray) -> tuple[NDArray, NDArray, int]:
    """(true star indices, their centroids (M, 2), crowded stars left out) of an image."""
    rot_mid = Rotation.from_rotvec(-scene.omega_rad_s * scene.exposure_s / 2)
    true_xy = np.stack(scene.camera.vector_to_pixel(rot_mid.apply(scene.rot_start.apply(scene.icrs))), axis=1)
    index = match_truth(true_xy[:, 0], true_xy[:, 1], found_xy[:, 0], found_xy[:, 1], params["match_px"])
    gaps = np.linalg.norm(true_xy[:, None] - true_xy[None], axis=2) + np.diag(np.full(len(true_xy), np.inf))
    crowded = np.min(gaps, axis=1) < params["crowd_px"]
    keep = (index >= 0) & ~crowded
    return np.flatnonzero(keep), found_xy[index[keep]], int(np.count_nonzero(crowded))


def centroids_xy(params: Mapping[str, Any], image: NDArray) -> NDArray[np.float64]:
    """The measured star positions (N, 2) of an image by the trial's ``centroider``."""
    if params["centroider"] == "moments":
        regions = find_streaks(image, min_area_px=params["min_area_px"]).regions
        return np.array([r.centroid_xy for r in regions]).reshape(-1, 2)
    found = StarDetector(centroid=params["centroider"], min_area_px=params["min_area_px"]).detect(image)
    return np.stack([found.x, found.y], axis=1).reshape(-1, 2)


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """One smeared image starting at ``rot``, centroided and scored."""
    scene = draw_image(params, rot, rng)
    camera = scene.camera
    t0 = time.perf_counter()
    found = centroids_xy(params, scene.image)
    elapsed = time.perf_counter() - t0
    stars, xy, crowded = matched(params, scene, found)
    truth_mid = Rotation.from_rotvec(-scene.omega_rad_s * scene.exposure_s / 2) * scene.rot_start
    paths = star_paths(camera, scene.omega_rad_s, scene.exposure_s, scene.rot_start.apply(scene.icrs), 9)
    row = {"error": "", "sigma_cross_arcsec": NAN, "sigma_roll_arcsec": NAN, "n_stars": len(found),
           "n_matched": len(stars), "false_match_prob": NAN, "time_s": elapsed, **truth_columns(truth_mid),
           "smear_px": float(np.max(np.linalg.norm(paths[:, -1] - paths[:, 0], axis=1))), "n_crowded": crowded}
    if len(stars) < 3:
        row.update(status="TOO_FEW_STARS", solved=False, **error_columns(truth_mid, None, camera, tolerance_px),
                   sigma_urad=NAN, std_urad=NAN, std_truth_urad=NAN)
        return TrialOutput(row, image=scene.image, truth=scene.truth)
    measured = camera.pixel_to_vector(xy[:, 0], xy[:, 1])
    fit = require(solve_wahba(measured, scene.icrs[stars]).rotation, "the attitude of three or more stars")
    row.update(status="OK", solved=True, **error_columns(truth_mid, fit, camera, tolerance_px),
               sigma_urad=1e6 * interstar_rms_rad(measured, truth_mid.apply(scene.icrs[stars])),
               std_urad=1e6 * image_rms_rad(camera, xy, fit.apply(scene.icrs[stars])),
               std_truth_urad=1e6 * image_rms_rad(camera, xy, truth_mid.apply(scene.icrs[stars])))
    return TrialOutput(row, image=scene.image, truth=scene.truth)


def check(params: Mapping[str, Any]) -> None:
    """Refuse an empty electrons range."""
    check_range(params, "star_electrons")


COLUMNS = {"sigma_urad": pa.float64(), "std_urad": pa.float64(), "std_truth_urad": pa.float64(),
           "smear_px": pa.float64(), "n_crowded": pa.int32()}

LEVEL = register(Level(
    name="smear", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns=COLUMNS, chunk_trials=20))

