"""A solve job's solution kept on disk (``record.npz``), and the analysis record rebuilt from it.

The post-processing analyses (:mod:`startrack.analysis.postprocess`) read
:class:`~startrack.analysis._records.ImageRecord` objects: the solution with its detections and
camera, the pixels (or the file to read them from), the time, the site, the true attitude of a
simulated image and the settings. A job keeps all of it: the upload itself (``input.*``), the
options in ``job.json`` and the full :class:`~startrack.results.AttitudeSolution` in
``record.npz`` (every array of the detections and matches, the camera's fields, the attitude
quaternion and covariance), so an analysis never solves an image again to learn what the job
found.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np
from astropy.time import Time
from scipy.spatial.transform import Rotation

from ..calibrate import Site
from ..camera import Camera
from ..results import AttitudeSolution, Detections, StarMatches, Status
from ._jobs import read_json

FORMAT_VERSION = 1
_DET_ARRAYS = ("x", "y", "flux", "sigma_px", "area_px", "peak", "elongation")
_DET_SCALARS = ("background", "noise", "width", "height")
_SCALARS = ("ra_deg", "dec_deg", "roll_deg", "fov_deg", "false_match_prob", "solve_time_s", "epoch_jyear")


def save_solution(path: Path, solution: AttitudeSolution, extra: dict[str, Any] | None = None) -> None:
    """Write ``solution`` (with its detections, matches and camera) to ``path`` (.npz).

    ``extra`` (JSON-able: the time, the true attitude) is stored beside it."""
    arrays: dict[str, Any] = {}
    det = solution.detections or Detections()
    for key in _DET_ARRAYS:
        arrays[f"det_{key}"] = getattr(det, key)
    m = solution.matches
    arrays.update(match_det_index=m.det_index, match_hip=m.hip, match_cat_vectors=m.cat_vectors,
                  residuals_arcsec=solution.residuals_arcsec)
    if solution.rot_cam_from_icrs is not None:
        arrays["quat_xyzw"] = solution.rot_cam_from_icrs.as_quat()
    if solution.covariance_rad2 is not None:
        arrays["covariance_rad2"] = solution.covariance_rad2
    meta = {"version": FORMAT_VERSION, "status": solution.status.value, "reason": solution.reason,
            "matches_status": m.status.value, "matches_reason": m.reason, "matches_fmp": m.false_match_prob,
            "has_detections": solution.detections is not None, "epoch_source": solution.epoch_source,
            "fov_source": solution.fov_source,
            "guided_stars": int(solution.guided_stars), "detections": {k: float(getattr(det, k)) for k in _DET_SCALARS},
            "camera": None if solution.camera is None else _camera_fields(solution.camera),
            **{k: _plain(getattr(solution, k)) for k in _SCALARS}, "extra": extra or {}}
    with open(path, "wb") as fh:
        np.savez(fh, meta=np.array(json.dumps(meta)), **arrays)


def _plain(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def _camera_fields(camera: Camera) -> dict[str, Any]:
    return {k: (float(v) if isinstance(v, float | np.floating) else v) for k, v in dataclasses.asdict(camera).items()}


def _nan(value: float | None) -> float:
    return float("nan") if value is None else float(value)


def load_solution(path: Path) -> tuple[AttitudeSolution, dict[str, Any]]:
    """The solution written by :func:`save_solution`, and its ``extra``."""
    with np.load(path, allow_pickle=False) as data:
        meta = json.loads(str(data["meta"]))
        arrays = {k: data[k] for k in data.files if k != "meta"}
    d = meta["detections"]
    detections = Detections(**{k: arrays[f"det_{k}"] for k in _DET_ARRAYS}, background=d["background"],
                            noise=d["noise"], width=int(d["width"]), height=int(d["height"]))
    matches = StarMatches(status=Status(meta["matches_status"]), reason=meta["matches_reason"],
                          det_index=arrays["match_det_index"], hip=arrays["match_hip"],
                          cat_vectors=arrays["match_cat_vectors"], false_match_prob=meta["matches_fmp"])
    quat = arrays.get("quat_xyzw")
    solution = AttitudeSolution(
        status=Status(meta["status"]), reason=meta["reason"],
        rot_cam_from_icrs=None if quat is None else Rotation.from_quat(quat),
        covariance_rad2=arrays.get("covariance_rad2"),
        **{k: _nan(meta.get(k)) for k in _SCALARS},
        camera=None if meta["camera"] is None else Camera(**meta["camera"]), matches=matches,
        residuals_arcsec=arrays["residuals_arcsec"], epoch_source=meta.get("epoch_source", ""),
        fov_source=meta.get("fov_source", ""),
        guided_stars=int(meta.get("guided_stars", 0)), detections=detections if meta["has_detections"] else None)
    return solution, meta["extra"]


def job_record(folder: Path):
    """The :class:`~startrack.analysis._records.ImageRecord` of a finished solve job's folder.

    The pixels are not loaded (``path`` points at the upload; the analyses read it when they need
    it). Raises FileNotFoundError when the job wrote no ``record.npz`` (it failed before
    detection)."""
    from ..analysis import ImageRecord

    meta = read_json(folder / "job.json")
    solution, extra = load_solution(folder / "record.npz")
    options = meta["options"]
    given = extra.get("camera_given")  # the camera the final solve was given (None: FOV searched)
    camera = None if given is None else Camera(**given)
    site = None if options.get("site") is None else Site(**options["site"])
    true_q = extra.get("true_quat_xyzw")
    settings = {"fov_deg": options.get("fov_deg"), "fov_range_deg": options.get("fov_range_deg"),
                "camera": None if camera is None else camera.name, "method": options.get("method"),
                "channel": options.get("channel"), "epoch_jyear": extra.get("epoch_jyear"),
                "detector": extra.get("detector_changed", {}), "detection_preset": options.get("detection_preset"),
                "lens_correction": options.get("lens_correction"),
                "atmosphere_correction": options.get("atmosphere_correction"), "job": meta["id"]}
    return ImageRecord(
        name=meta.get("label") or meta["id"], solution=solution, settings=settings,
        path=folder / meta["input"], camera=camera, site=site,
        time=None if extra.get("time_utc") is None else Time(extra["time_utc"], scale="utc"),
        true_rot_cam_from_icrs=None if true_q is None else Rotation.from_quat(true_q))
