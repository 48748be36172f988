"""The result files of a solve job and its ``result`` object (the API's ``result`` key).

=================  ===========================================================================
``result.json``    the result object (:func:`result_dict`)
``solution.json``  :func:`startrack.io._solution_json.solution_to_dict` (matches with x, y) plus
                   the ground-photo and truth keys of the result
``solution.wcs``   header-only FITS with the image's TAN(-SIP) WCS (:mod:`startrack.io._wcs`),
                   FITS 1-based pixels; only when solved
``matches.csv``    x, y (0-based px), hip, ra_deg, dec_deg (catalog, ICRS at the solve epoch),
                   v_mag, residual_arcsec
``detections.csv`` every kept detection: index, x, y, flux, sigma_px, area_px, peak, elongation,
                   mag (instrument), peak_snr, psf_sigma_px, hip (empty when not matched)
``rejected.csv``   the spots the detector refused: x, y, area_px, peak, elongation, category, reason
``rerun.json``     what repeats the job: the upload's SHA-256, the options, the detector's full
                   settings, the package version
``record.npz``     the full solution, read back by the analyses (:mod:`._records`)
=================  ===========================================================================
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..analysis.postprocess import csv_cell
from ..camera import Camera
from ..catalog import constellation_of, load_catalog
from ..detect import DetectionDetails
from ..errors import require
from ..frames import vector_to_radec
from ..io import atomic_path, solution_to_dict, write_wcs
from ..results import AttitudeSolution, Status
from ._jobs import write_json


def num(value: Any) -> float | None:
    """A finite float, else None (JSON null)."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def failure_words(solution: AttitudeSolution, n_detected: int) -> str | None:
    """Why an image was not solved, in a few words (None when solved)."""
    if solution.solved:
        return None
    if solution.status is Status.TOO_FEW_STARS:
        return "no stars found" if n_detected == 0 else f"too few stars ({n_detected} found)"
    if solution.status is Status.TIMEOUT:
        return "timed out"
    if solution.status is Status.DEGENERATE or "ambiguous" in solution.reason.lower():
        return "ambiguous"
    return "no pattern matched"


def result_dict(solution: AttitudeSolution, times_s: dict[str, float], extra: dict[str, Any]) -> dict[str, Any]:
    """The ``result`` object of ``GET /api/jobs/{id}`` (documented in ``docs/web.md``)."""
    det = solution.detections
    n_det = 0 if det is None else len(det)
    out: dict[str, Any] = {"status": solution.status.value, "reason": solution.reason,
                           "failure": failure_words(solution, n_det), "n_detected": n_det,
                           "n_matched": len(solution.matches) if solution.solved else 0,
                           "epoch_jyear": num(solution.epoch_jyear), "epoch_source": solution.epoch_source,
                           "fov_source": solution.fov_source,
                           "guided_stars": int(solution.guided_stars)}
    keys = ("ra_deg", "dec_deg", "constellation", "roll_deg", "fov_deg", "qx", "qy", "qz", "qw", "false_match_prob",
            "residual_arcsec", "sigma_cross_boresight_arcsec", "sigma_roll_arcsec", "focal_px", "mirrored")
    out.update(dict.fromkeys(keys))
    if solution.solved:
        qx, qy, qz, qw = require(solution.quaternion_xyzw, "a solved frame's quaternion")
        out.update(ra_deg=num(solution.ra_deg), dec_deg=num(solution.dec_deg),
                   constellation=constellation_of(solution.ra_deg, solution.dec_deg), roll_deg=num(solution.roll_deg),
                   fov_deg=num(solution.fov_deg), qx=float(qx), qy=float(qy), qz=float(qz), qw=float(qw),
                   false_match_prob=num(solution.false_match_prob),
                   residual_arcsec=num(np.sqrt(np.mean(solution.residuals_arcsec**2))),
                   sigma_cross_boresight_arcsec=num(solution.sigma_cross_boresight_arcsec),
                   sigma_roll_arcsec=num(solution.sigma_roll_arcsec), focal_px=num(_camera(solution).fx),
                   mirrored=bool(_camera(solution).mirrored))
    out["times_s"] = {k: round(v, 6) for k, v in times_s.items()}
    out.update(extra)
    return out


def write_table(path: Path, columns: dict[str, list]) -> None:
    """Columns as CSV (the analyses' cell format: full precision, empty for NaN), atomically."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(list(columns))
        for row in zip(*columns.values(), strict=True):
            writer.writerow([csv_cell(v) for v in row])


def matches_table(solution: AttitudeSolution) -> dict[str, list]:
    """x, y, hip, ra_deg, dec_deg, v_mag, residual_arcsec of each matched star."""
    cols: dict[str, list] = {k: [] for k in ("x", "y", "hip", "ra_deg", "dec_deg", "v_mag", "residual_arcsec")}
    if not solution.solved:
        return cols
    det, m = require(solution.detections, "a solved frame's detections"), solution.matches
    catalog = load_catalog()
    ra, dec = vector_to_radec(m.cat_vectors)
    mags = catalog.v_mag[np.searchsorted(catalog.hip, m.hip)]
    for k, i in enumerate(m.det_index):
        for key, value in (("x", det.x[i]), ("y", det.y[i]), ("hip", int(m.hip[k])), ("ra_deg", np.degrees(ra[k])),
                           ("dec_deg", np.degrees(dec[k])), ("v_mag", mags[k]),
                           ("residual_arcsec", solution.residuals_arcsec[k])):
            cols[key].append(value)
    return cols


def detections_table(details: DetectionDetails, solution: AttitudeSolution) -> dict[str, list]:
    """Every kept detection with its measurements and the HIP number it was matched to."""
    det = solution.detections if solution.detections is not None else details.detections
    hip = np.full(len(det), -1, dtype=np.int64)
    if solution.solved:
        hip[solution.matches.det_index] = solution.matches.hip
    cols: dict[str, list] = {"index": list(range(len(det)))}
    for key in ("x", "y", "flux", "sigma_px", "area_px", "peak", "elongation"):
        cols[key] = getattr(det, key).tolist()
    guided = solution.guided_stars  # the last rows: measured where the solution predicts them
    blind = len(det) - guided
    # the solve's detections are the detect stage's (deterministic), unless it solved a second
    # detection (startrack.solve._second_detection): then the stage's measurements are not theirs
    same = len(details) == blind and bool(np.array_equal(det.x[:blind], details.detections.x)
                                          and np.array_equal(det.y[:blind], details.detections.y))
    for key in ("mag", "peak_snr", "psf_sigma_px"):
        cols[key] = (getattr(details, key).tolist() if same else [None] * blind) + [None] * guided
    cols["hip"] = [int(h) if h >= 0 else None for h in hip]
    cols["guided"] = [False] * blind + [True] * guided
    return cols


def _camera(solution: AttitudeSolution) -> Camera:
    """The camera of a solved frame."""
    return require(solution.camera, "a solved frame's camera")


def write_solution_files(folder: Path, solution: AttitudeSolution, details: DetectionDetails,
                         rejects: dict[str, list], result: dict[str, Any], date_obs: str | None) -> None:
    """solution.json, solution.wcs (when solved), matches.csv, detections.csv, rejected.csv."""
    extra = {k: result.get(k) for k in ("altitude_deg", "azimuth_deg", "time_utc", "site", "truth")}
    write_json(folder / "solution.json", {**solution_to_dict(solution, solution.detections), **extra})
    if solution.solved:
        write_wcs(folder / "solution.wcs", solution.rot_cam_from_icrs, _camera(solution), date_obs=date_obs)
    write_table(folder / "matches.csv", matches_table(solution))
    write_table(folder / "detections.csv", detections_table(details, solution))
    write_table(folder / "rejected.csv", rejects)


def rerun_dict(meta: dict[str, Any], detector_settings: dict[str, Any], auto: dict[str, Any] | None) -> dict[str, Any]:
    """Everything needed to repeat the job (``rerun.json``)."""
    settings = {k: (list(v) if isinstance(v, tuple) else v) for k, v in detector_settings.items()}
    return {"startrack_version": __version__, "kind": meta["kind"], "created": meta["created"],
            "input": {k: meta.get(k) for k in ("label", "sha256", "bytes", "format", "width", "height")},
            "simulate": meta.get("simulate"), "options": meta["options"], "detector": settings, "auto": auto,
            "repeat": "POST /api/jobs with this file and 'options' gives the same result; "
                      "startrack.solve_image on the file with detector=startrack.detect.StarDetector(**detector) "
                      "and the job's solver options gives its identify stage's solution (before fit_camera)"}
