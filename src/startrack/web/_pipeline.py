"""One solve job, stage by stage, in a worker process; each stage's start is written to state.json.

=============  =================================================================================
``read``       render the scene first when the job simulates one (:mod:`._simulation`); read the
               file (:func:`startrack.io.read_image`)
``detect``     the detector of the job's preset and settings (``auto``: from the image,
               :mod:`._presets`), detection with details, and the refused spots (:mod:`._rejects`)
``identify``   lost-in-space identification and fit: :func:`startrack.solve_image` with the job's
               detector, exactly as ``startrack solve`` does (it detects again, deterministically
               the same spots, so that the solver's own ordering of them and its reading of the
               epoch from the header are the library's, not a copy of them)
``attitude``   the attitude as seen from the ground for a photo with a site and time
               (:func:`startrack.calibrate._ground_solve.solve_ground_photo`: apparent place and
               refraction, then altitude and azimuth; without the atmosphere correction only
               :func:`~startrack.calibrate._ground.pointing_altaz`), and the error against the truth
               of a simulated file
``refine``     with ``fit_camera``: focal length and distortion fitted on the matched stars
               (:func:`startrack.calibrate._stars.calibrate_from_stars` with
               :mod:`startrack.calibrate._selfcal`'s choice of terms and F-test), the image solved
               again with that camera, kept if it matches at least as many stars; else skipped
``annotate``   the annotated frame and the result files (:mod:`._annotate`, :mod:`._outputs`)
=============  =================================================================================

The job ends ``done`` when the image is solved and ``failed`` otherwise, with the reason in
words ("no stars found", "too few stars (3 found)", "no pattern matched", "ambiguous", "timed
out") followed by the solver's own sentence; the files are written in both cases.
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from astropy.time import Time

from ..analysis.postprocess import error_arcsec, pinhole, true_rotation_from_file
from ..calibrate import Site, pointing_altaz, time_from_header
from ..camera import Camera
from ..detect import StarDetector
from ..errors import InvalidInputError, require
from ..identify import check_method
from ..io import Image, read_image
from ..results import AttitudeSolution
from ..solve import DEFAULT_EPOCH_JYEAR, solve_image
from ._annotate import write_annotated
from ._jobs import SOLVE_STAGES, now_iso, read_json, update_state, write_json
from ._outputs import num, rerun_dict, result_dict, write_solution_files
from ._presets import auto_settings, preset_detector
from ._records import save_solution
from ._rejects import rejected_spots, without_solved

STAGES = SOLVE_STAGES
WEIGHTS = {"read": 0.10, "detect": 0.15, "identify": 0.35, "attitude": 0.10, "refine": 0.15, "annotate": 0.15}
"""Share of a typical job's time per stage, for the progress fraction."""


@dataclass
class _Job:
    """A running job: its folder, what was asked, the per-stage times so far."""

    folder: Path
    meta: dict[str, Any]
    times: dict[str, float] = field(default_factory=dict)

    @property
    def options(self) -> dict[str, Any]:
        return self.meta["options"]

    @contextmanager
    def stage(self, name: str):
        done = sum(WEIGHTS[s] for s in STAGES[:STAGES.index(name)])
        update_state(self.folder, stage=name, progress=round(done, 3), times_s=self.times)
        t0 = time.perf_counter()
        yield
        self.times[name] = time.perf_counter() - t0


def run_solve_job(folder: Path) -> None:
    """Run the solve job in ``folder`` to its end state (module docstring)."""
    job = _Job(folder, read_json(folder / "job.json"))
    opts = job.options
    with job.stage("read"):
        image = _read(job)
    with job.stage("detect"):
        detector, auto = _detector(image.data, opts)
        detector = detector.for_image(image)  # a JPEG's noise floor, for every later detection too
        details = detector.detect_details(image.data)
        rejects = rejected_spots(image.data, detector, details.detections)
    when, site = _when(opts, image), _site(opts)
    epoch = opts["epoch"] if opts["epoch"] is not None else (None if opts["time"] is None else when)
    fov = _fov_kwargs(opts, image)
    with job.stage("identify"):
        solution = _identify(image, detector, fov, epoch, opts)
    epoch = solution.epoch_jyear if math.isfinite(solution.epoch_jyear) else DEFAULT_EPOCH_JYEAR
    with job.stage("attitude"):
        solution, extra = _attitude(solution, image, detector, fov, when, site, opts)
    camera_fit = None
    with job.stage("refine"):
        if opts["fit_camera"] and solution.solved:
            solution, extra, camera_fit, fov = _refine(solution, image, detector, fov, epoch, when, site, opts)
    with job.stage("annotate"):
        result = _write_files(job, image, solution, details, rejects, detector, auto, camera_fit, fov, when,
                              epoch, extra)
    result["times_s"] = {k: round(v, 6) for k, v in job.times.items()}
    write_json(folder / "result.json", result)
    error = None if solution.solved else f"{result['failure']}: {solution.reason}"
    update_state(folder, state="done" if solution.solved else "failed", stage=None, progress=1.0, error=error,
                 times_s=result["times_s"], finished=now_iso())


def _read(job: _Job) -> Image:
    path = job.folder / job.meta["input"]
    if job.meta.get("simulate") is not None and not path.exists():
        from ._simulation import render

        render(job.meta["simulate"], path)
    return read_image(path, channel=job.options["channel"])


def _detector(data: np.ndarray, opts: dict[str, Any]) -> tuple[StarDetector, dict[str, Any] | None]:
    settings = {k: tuple(v) if isinstance(v, list) else v for k, v in opts["detection"].items()}
    if opts["detection_preset"] != "auto":
        return preset_detector(opts["detection_preset"], settings), None
    auto = auto_settings(data, settings)
    chosen = {k: auto[k] for k in ("sigma", "min_area_px") if k not in settings}
    return StarDetector(**{**settings, **chosen}), auto


def _when(opts: dict[str, Any], image: Image) -> Time | None:
    """The exposure time: the option, else the header's (None when it has none)."""
    if opts["time"] is not None:
        return Time(opts["time"], scale="utc")
    try:
        return time_from_header(image.header, utc_offset_hours=opts["utc_offset_hours"])
    except InvalidInputError:
        return None


def _site(opts: dict[str, Any]) -> Site | None:
    return None if opts["site"] is None else Site(**opts["site"])


def _fov_kwargs(opts: dict[str, Any], image: Image) -> dict[str, Any]:
    """``fov_deg`` / ``fov_range_deg`` / ``camera`` for the solver (the camera's pinhole without
    the lens correction), checked against the image size."""
    camera = None if opts["camera"] is None else Camera(**opts["camera"])
    if camera is not None:
        if (camera.width, camera.height) != (image.width, image.height):
            raise InvalidInputError(f"camera {camera.name!r} is {camera.width} x {camera.height} px but the image "
                                    f"is {image.width} x {image.height} px")
        if not opts["lens_correction"]:
            camera = pinhole(camera)
    fov_range = None if opts["fov_range_deg"] is None else tuple(opts["fov_range_deg"])
    return {"fov_deg": opts["fov_deg"], "fov_range_deg": fov_range, "camera": camera}


def _identify(image: Image, detector: StarDetector, fov: dict[str, Any], epoch, opts: dict[str, Any]
              ) -> AttitudeSolution:
    """:func:`startrack.solve_image` of the job (epoch None: from the header, else J2000.0)."""
    return solve_image(image, detector=detector, epoch=epoch, method=check_method(opts["method"]),
                       guided=opts.get("guided", False), **fov)


def _attitude(solution: AttitudeSolution, image: Image, detector: StarDetector, fov: dict[str, Any],
              when: Time | None, site: Site | None, opts: dict[str, Any]) -> tuple[AttitudeSolution, dict[str, Any]]:
    """Ground-photo attitude and altitude / azimuth, and the truth error (module docstring)."""
    extra: dict[str, Any] = {"altitude_deg": None, "azimuth_deg": None, "time_utc": None if when is None else
                             when.utc.isot, "site": None if site is None else site.name, "ground_note": None}
    if solution.solved and site is not None:
        if when is None:
            extra["ground_note"] = "no altitude / azimuth: the file has no time and options.time was not given"
        elif opts["atmosphere_correction"]:
            from ..calibrate import solve_ground_photo

            ground = solve_ground_photo(image, site, time=when, detector=detector, method=opts["method"],
                                        guided=opts.get("guided", False), **fov)
            if ground.solution.solved:
                solution = replace(ground.solution, solve_time_s=solution.solve_time_s)
                extra.update(altitude_deg=num(ground.altitude_deg), azimuth_deg=num(ground.azimuth_deg))
        else:
            alt, az = pointing_altaz(solution.rot_cam_from_icrs, when, site)
            extra.update(altitude_deg=num(alt), azimuth_deg=num(az))
    extra["truth"] = _truth_error(solution, image)
    return solution, extra


def _truth_error(solution: AttitudeSolution, image: Image) -> dict[str, Any] | None:
    truth = true_rotation_from_file(image)
    if truth is None:
        return None
    quat = truth.as_quat(canonical=True)
    out: dict[str, Any] = {k: float(q) for k, q in zip(("qx", "qy", "qz", "qw"), quat, strict=True)}
    if solution.solved:
        total, pointing, roll = error_arcsec(solution.rot_cam_from_icrs, truth)
        out.update(error_total_arcsec=total, error_pointing_arcsec=pointing, error_roll_arcsec=roll,
                   error_px=total / require(solution.camera, "a solved frame's camera").pixel_scale_arcsec)
    return out


def _refine(solution, image, detector, fov, epoch, when, site, opts):
    """Fit the camera on the matched stars and solve again with it (module docstring)."""
    from ..calibrate import (
        DEFAULT_FIT,
        CalibrationFrame,
        affordable_fit,
        calibrate_from_stars,
        justified,
        pinhole_of,
    )

    frame = CalibrationFrame.from_solution(solution)
    cal = calibrate_from_stars(frame, pinhole_of(solution.camera), fit=affordable_fit(DEFAULT_FIT, len(frame)))
    cal = justified(frame, cal) if cal.status else cal
    info: dict[str, Any] = {"fitted": list(cal.fitted), "rms_px": num(cal.rms_px), "reason": cal.reason,
                            "matches_before": len(solution.matches), "kept": False}
    if not cal.status:
        return solution, _attitude(solution, image, detector, fov, when, site, opts)[1], info, fov
    new_fov = {"fov_deg": None, "fov_range_deg": None, "camera": cal.camera}
    again = _identify(image, detector, new_fov, epoch, opts)
    info.update(matches_after=len(again.matches) if again.solved else 0, fov_deg=num(cal.camera.fov_deg),
                k1=num(cal.camera.k1), k2=num(cal.camera.k2))
    if not (again.solved and len(again.matches) >= len(solution.matches)):
        return solution, _attitude(solution, image, detector, fov, when, site, opts)[1], info, fov
    info["kept"] = True
    again, extra = _attitude(again, image, detector, new_fov, when, site, opts)
    return again, extra, info, new_fov


def _write_files(job: _Job, image: Image, solution, details, rejects, detector, auto, camera_fit, fov, when,
                 epoch, extra) -> dict[str, Any]:
    """Every result file but result.json; returns the result object."""
    folder = job.folder
    truth_xy = _truth_xy(folder / job.meta["input"])
    shown = details.detections if solution.detections is None else solution.detections  # + guided stars
    rejects = without_solved(rejects, solution.detections)
    write_annotated(folder / "annotated.png", image.data, solution, shown, rejects, truth_xy)
    result = result_dict(solution, job.times, {**extra, "n_rejected": len(rejects["x"]), "auto": auto,
                                                "mosaic": image.mosaic,
                                                "camera_fit": camera_fit, "detection_preset":
                                                job.options["detection_preset"]})
    write_solution_files(folder, solution, details, rejects, result, None if when is None else when.utc.isot)
    default = StarDetector().settings()
    changed = {k: (list(v) if isinstance(v, tuple) else v) for k, v in detector.settings().items()
               if v != default[k]}
    given = fov["camera"]
    truth = extra.get("truth")
    save_solution(folder / "record.npz", solution, {
        "epoch_jyear": epoch, "time_utc": extra.get("time_utc"), "detector_changed": changed,
        "camera_given": None if given is None else _camera_json(given),
        "true_quat_xyzw": None if truth is None else [truth[k] for k in ("qx", "qy", "qz", "qw")]})
    write_json(folder / "rerun.json", rerun_dict(job.meta, detector.settings(), auto))
    return result


def _camera_json(camera: Camera) -> dict[str, Any]:
    from ._options import camera_to_json

    return camera_to_json(camera)


def _truth_xy(path: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """True star positions from the ``TRUTH`` table of a FITS file written by ``startrack simulate``."""
    if path.suffix != ".fits":
        return None
    from astropy.io import fits

    try:
        with fits.open(path, memmap=False) as hdus:
            if "TRUTH" not in hdus:
                return None
            table = hdus["TRUTH"].data
            return np.asarray(table["x"], float), np.asarray(table["y"], float)
    except (OSError, KeyError, ValueError):
        return None
