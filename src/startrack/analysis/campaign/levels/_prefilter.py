"""Level "prefilter": the time of Huffman 2006's 5 x 5 statistical pre-filter, and the stars the
detector then centroids, on a rendered frame of the sky (Huffman 2006 §7.1.1, Table 7.2).

The frame is the image level's (:func:`.image.render`: every simulator setting of that level is
a parameter here), at the trial's attitude or at a fixed pointing (``pointing_radec_roll_deg``)
turned about camera y by a uniform angle up to ``pointing_spread_deg``: the frames of a slow
pass over one field, as the seed's 14-frame sequence was. The ``StarDetector`` of the ``detect_*`` settings
(for the seed's experiment ``detect_threshold = "prefilter-window"`` or ``"prefilter-grid"``,
the per-candidate ``starCentroid2`` and the grid-of-tiles ``starCentroid3`` forms, with
``detect_pixel_sigma`` the single-pixel k) detects the frame, timed whole; then the pre-filter
alone is timed on the same single-pixel candidate mask (:func:`candidate_mask`, the detector's
own steps up to the pre-filter). Each star centred in the image takes its nearest detection
within ``match_px``.

Common columns (no identification): ``status`` "OK" when a true star was found (else
"TOO_FEW_STARS"); ``correct`` = no detection but true stars (no noise spike centroided as a
star: the seed's finding at k = 1); ``n_stars`` the detections (the seed's "stars centroided"),
``n_matched`` the true stars found; ``time_s`` the whole detection; the true attitude. Extra
columns: ``time_prefilter_s``, ``n_candidates`` (pixels above k sigma before the pre-filter),
``n_truth`` (stars centred in the image), ``time_render_s``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ....detect import (
    PREFILTER_FORMS,
    StarDetector,
    background_model,
    detection_image,
    noise_floor,
    pixel_noise,
    prefilter,
    preprocess,
)
from ....frames import rotation_from_radec_roll
from .._params import Param, SpecError, params_by_name
from . import Level, TrialOutput, register
from ._image import PARAMS as IMAGE_PARAMS
from ._image import check as check_image
from ._image import render
from ._measure import match_truth, measurement_columns
from ._scene import frame_detector

SOLVER_ONLY = ("fov_known", "fov_range_deg", "method", "calibrated", "solver_epoch_jyear", "distortion_known",
               "timing_error_s", "frames_per_attitude", "attitudes_per_field", "dither_px")
"""Parameters of the image level that only tell the solver something (this level does not solve)."""
PARAMS = params_by_name(tuple(p for p in IMAGE_PARAMS.values() if p.name not in SOLVER_ONLY), (
    Param("match_px", "float", 3.0, "largest distance from a true star to its detection (px)", lo=0.1, hi=100.0),
    Param("pointing_radec_roll_deg", "floats", None, "a fixed pointing (RA, Dec, roll, deg); auto: the trial's "
          "attitude", lo=-360.0, hi=360.0, length=3, optional=True),
    Param("pointing_spread_deg", "float", 0.0, "a fixed pointing is turned about camera y by a uniform angle "
          "in [0, this] (the frames of a slow pass, deg)", lo=0.0, hi=180.0),
))


def trial_pointing(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator) -> Rotation:
    """``rot_cam_from_icrs`` of the frame: the trial's attitude, or the fixed pointing turned by a
    random angle of the spread about camera y (drawn from ``rng``)."""
    fixed = params["pointing_radec_roll_deg"]
    if fixed is None:
        return rot
    start = rotation_from_radec_roll(*np.radians(fixed))
    return Rotation.from_rotvec([0.0, np.radians(rng.uniform(0.0, params["pointing_spread_deg"])), 0.0]) * start


def candidate_mask(cfg: StarDetector, image: NDArray) -> NDArray[np.bool_]:
    """The single-pixel ``pixel_sigma`` mask the pre-filter works on, as the detector makes it
    (:mod:`startrack.detect._pipeline`: prepare, background of the detection image, pixel noise)."""
    prepared, _ = preprocess(cfg, image, None)
    data = prepared.data
    binning = min(cfg.binning, *data.shape)
    det = detection_image(data, binning, cfg.kernel, cfg.kernel_px, prepared.invalid)
    model = background_model(cfg, det, binning)
    noise_px = pixel_noise(data, model) or noise_floor(data, model.level)
    level, noise = model.maps(np.arange(data.shape[0]), np.arange(data.shape[1]))
    with np.errstate(invalid="ignore"):
        return (data - level) > cfg.pixel_sigma * noise_px / model.noise * np.asarray(noise)


def run(params: Mapping[str, Any], rot: Rotation, rng: np.random.Generator, tolerance_px: float) -> TrialOutput:
    """Render one frame at ``rot``, detect it, time its pre-filter (``tolerance_px`` is not used)."""
    rot = trial_pointing(params, rot, rng)
    t0 = time.perf_counter()
    sim = render(params, rot, rng)
    t1 = time.perf_counter()
    cfg = frame_detector(params)
    found = cfg.detect(sim.image)
    t2 = time.perf_counter()
    mask = candidate_mask(cfg, sim.image)
    t3 = time.perf_counter()
    prefilter(mask, cfg.threshold.removeprefix("prefilter-"), cfg.prefilter_count)
    t4 = time.perf_counter()
    inside = sim.truth.inside()
    index = match_truth(sim.truth.x[inside], sim.truth.y[inside], found.x, found.y, params["match_px"])
    n_found = int(np.count_nonzero(index >= 0))
    row = measurement_columns(status="OK" if n_found else "TOO_FEW_STARS", correct=len(found) == n_found,
                              n_stars=len(found), n_matched=n_found, time_s=t2 - t1, rot_cam_from_icrs=rot)
    row.update(time_prefilter_s=t4 - t3, n_candidates=int(np.count_nonzero(mask)),
               n_truth=int(np.count_nonzero(inside)), time_render_s=t1 - t0)
    return TrialOutput(row, image=sim.image, truth=sim.truth)


def check(params: Mapping[str, Any]) -> None:
    """The image level's checks, and a pre-filter threshold (the level times the pre-filter)."""
    check_image({**params, **{name: IMAGE_PARAMS[name].default for name in SOLVER_ONLY}})
    if not params["detect_threshold"].startswith("prefilter-"):
        raise SpecError(f"detect_threshold must be one of {', '.join(map(repr, _FORMS))} at this level "
                        f"(it times the pre-filter), got {params['detect_threshold']!r}")


_FORMS = tuple(f"prefilter-{form}" for form in PREFILTER_FORMS)

LEVEL = register(Level(
    name="prefilter", doc=" ".join(__doc__.split("\n\n")[0].split()), params=PARAMS, run=run, check=check,
    columns={"time_prefilter_s": pa.float64(), "n_candidates": pa.int32(), "n_truth": pa.int32(),
             "time_render_s": pa.float64()}, chunk_trials=5))
