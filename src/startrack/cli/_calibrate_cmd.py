"""startrack calibrate IMAGE [IMAGE ...]: calibrate a camera from star images (each is solved
lost-in-space, then focal length, principal point, distortion and every attitude are fitted jointly,
the camera re-solves every image and the fit is repeated), or from checkerboard images with
--checkerboard COLSxROWS --square-mm S (OpenCV, Fowler 2013's method)."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..camera import Camera
from ..errors import InvalidInputError, require
from ..io import atomic_path, read_image
from ..solve import solve_image
from ._parser import CommandParser

if TYPE_CHECKING:
    from ..io import Image
    from ..results import AttitudeSolution
from ._common import (
    add_epoch_option,
    add_fov_options,
    add_max_pixels_option,
    apply_max_pixels_option,
    epoch_option,
    exit_status_epilog,
    fov_kwargs,
    non_empty,
    print_json,
)

PARAMETERS = ("f", "aspect", "cx", "cy", "k1", "k2", "k3", "p1", "p2")

OUTPUT = """\
output (table, the default)
  status, focal lengths fx fy (px) with the 1-sigma of f, principal point cx cy (0-based px),
  distortion k1 k2 k3 p1 p2, the terms pruned by the 3-sigma rule, the residual (px rms), and per
  image its solve status and matched stars.

output (--json)
  One object: status ("ok" or the failure), camera (the Camera fields: width, height, fx, fy, cx,
  cy, k1, k2, k3, p1, p2, ...), sigma (1-sigma of each fitted parameter: f px, aspect, cx, cy px,
  k1...), pruned, rms_px, n_outliers, and images: a list of {image, status, matches, ra_deg,
  dec_deg, roll_deg, qx, qy, qz, qw} (the attitude rot_cam_from_icrs of each solved image with the
  calibrated camera; null when not solved). Checkerboards: camera, sigma, pruned, rms_px,
  sigma_xy_px, used_views, rejected_views.

""" + exit_status_epilog("0 calibrated; 1 nothing could be solved or calibrated (the reason is printed); 2 misuse (bad "
                         "option, unreadable file, images of different sizes), one line on standard error;")


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack calibrate", description=__doc__, epilog=OUTPUT,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("images", nargs="+", help="star images (or checkerboard images with --checkerboard)")
    add_fov_options(parser)
    add_epoch_option(parser)
    parser.add_argument("--channel", choices=("r", "g", "b"), help="colour channel (default R + G + B)")
    parser.add_argument("--fit", default="f,aspect,cx,cy,k1,k2,p1,p2",
                        help="comma-separated parameters to fit, from " + ",".join(PARAMETERS) +
                             " (default %(default)s); insignificant ones are fixed at zero")
    parser.add_argument("--checkerboard", metavar="COLSxROWS", help="inner corners of a checkerboard, e.g. 9x6")
    parser.add_argument("--square-mm", type=float, help="checkerboard square size (default 25; with --checkerboard)")
    parser.add_argument("--out", metavar="CAMERA.json", type=non_empty, help="write the calibrated camera as JSON")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_max_pixels_option(parser)
    return parser


def _fit(text: str) -> tuple[str, ...]:
    names = tuple(t.strip() for t in text.split(",") if t.strip())
    bad = [n for n in names if n not in PARAMETERS]
    if bad or not names:
        raise InvalidInputError(f"--fit must name parameters among {','.join(PARAMETERS)}, got {text!r}")
    return names


def camera_to_dict(camera: Camera) -> dict[str, Any]:
    """The camera's fields as plain JSON values."""
    return {k: (float(v) if isinstance(v, float | np.floating) else v) for k, v in dataclasses.asdict(camera).items()}


def _calibrated(solutions, camera: Camera, fit: tuple[str, ...]) -> Any:
    """Joint calibration of solved images, fitted from the pinhole of ``camera``.

    Every round starts from the same null values (centred principal point, square pixels, no
    distortion; :func:`startrack.calibrate.pinhole_of`), as :func:`startrack.calibrate.self_calibrate`
    does: a term is pruned only when it is at its null value in the returned camera, and every other
    fitted term has its sigma. (From an earlier round's camera, cx, cy and aspect would be offsets
    from that round's values: near zero, always pruned, their values kept without an uncertainty.)

    Parameters
    ----------
    solutions : list of AttitudeSolution
        Solved images (``solve_image`` results, with their detections).
    camera : Camera
        Only its size and focal length start the fit.
    fit : tuple of str
        Parameters to fit, from :data:`PARAMETERS`.

    Returns
    -------
    CalibrationResult (of :func:`startrack.calibrate.calibrate_from_stars`)
        TOO_FEW_STARS when the stars cannot fix the unknowns.
    """
    from ..calibrate import CalibrationFrame, calibrate_from_stars, pinhole_of

    frames = [CalibrationFrame.from_solution(s) for s in solutions]
    return calibrate_from_stars(frames, pinhole_of(camera), fit=fit)


def _from_stars(args) -> dict[str, Any]:
    fit = _fit(args.fit)
    # the calibration fits a plain camera: a mirror image's solution would not give one
    solve_kw = {**fov_kwargs(args), "epoch": epoch_option(args), "parity": "normal"}
    images = [read_image(p, channel=args.channel) for p in args.images]
    _same_size(args.images, [img.data.shape[:2] for img in images])
    solutions = [_solved(path, img, **solve_kw) for path, img in zip(args.images, images, strict=True)]
    solved = [i for i, s in enumerate(solutions) if s.solved]
    if not solved:
        return {"status": "not_solved", "reason": "no image could be solved", "images": _per_image(args, solutions)}
    cameras = [require(solutions[i].camera, "a solved image's camera") for i in solved]
    start = Camera(width=cameras[0].width, height=cameras[0].height, fx=float(np.median([c.fx for c in cameras])))
    result = _calibrated([solutions[i] for i in solved], start, fit)
    if result.status:  # one self-improving round: re-solve with the calibrated camera, fit again
        calibrated = require(result.camera, "the calibrated camera")
        again = [_solved(args.images[i], images[i], camera=calibrated, epoch=solve_kw["epoch"], parity="normal")
                 for i in solved]
        if all(s.solved for s in again):
            solutions = [again[solved.index(i)] if i in solved else s for i, s in enumerate(solutions)]
            redo = _calibrated(again, calibrated, fit)
            result = redo if redo.status else result
    if not result.status:
        return {"status": result.status.value, "reason": result.reason, "images": _per_image(args, solutions)}
    camera = require(result.camera, "the calibrated camera")
    return {"status": "ok", "camera": camera_to_dict(camera), "sigma": result.sigma, "pruned": result.pruned,
            "rms_px": result.rms_px, "n_outliers": result.n_outliers, "images": _per_image(args, solutions)}


def _solved(path: str, image: Image, **kwargs) -> AttitudeSolution:
    """:func:`startrack.solve_image` of one image, a problem with its content named by its file."""
    try:
        return solve_image(image, **kwargs)
    except InvalidInputError as exc:  # no finite pixel, too small...
        raise InvalidInputError(f"{path}: {exc}") from exc


def _same_size(paths, shapes) -> None:
    for path, shape in zip(paths, shapes, strict=True):
        if shape != shapes[0]:
            raise InvalidInputError(f"all images must come from one camera at one size: {paths[0]} is "
                                    f"{shapes[0][1]} x {shapes[0][0]} px but {path} is {shape[1]} x {shape[0]} px")


def _per_image(args, solutions) -> list[dict[str, Any]]:
    out = []
    for path, sol in zip(args.images, solutions, strict=True):
        item: dict[str, Any] = {"image": str(path), "status": sol.status.value, "matches": len(sol.matches)}
        q = sol.quaternion_xyzw
        item.update({"ra_deg": sol.ra_deg if sol.solved else None, "dec_deg": sol.dec_deg if sol.solved else None,
                     "roll_deg": sol.roll_deg if sol.solved else None})
        item.update({k: (float(v) if q is not None else None)
                     for k, v in zip(("qx", "qy", "qz", "qw"), q if q is not None else [0] * 4, strict=True)})
        out.append(item)
    return out


DEFAULT_SQUARE_MM = 25.0
"""A checkerboard's square size when --square-mm is not given, mm."""


def _from_checkerboard(args) -> dict[str, Any]:
    from ..calibrate import Checkerboard, calibrate_checkerboard, find_corners

    try:
        cols, rows = (int(v) for v in args.checkerboard.lower().split("x"))
    except ValueError:
        raise InvalidInputError(f"--checkerboard must be COLSxROWS inner corners, e.g. 9x6, got "
                                f"{args.checkerboard!r}") from None
    board = Checkerboard(cols, rows, DEFAULT_SQUARE_MM if args.square_mm is None else args.square_mm)
    images = [read_image(p, channel=args.channel).data for p in args.images]
    _same_size(args.images, [img.shape for img in images])
    height, width = images[0].shape
    result = calibrate_checkerboard([find_corners(img, board) for img in images], board, width, height)
    camera = require(result.camera, "the calibrated camera")
    return {"status": "ok", "camera": camera_to_dict(camera), "sigma": result.sigma, "pruned": result.pruned,
            "rms_px": result.rms_px, "sigma_xy_px": list(result.sigma_xy_px),
            "used_views": [str(args.images[i]) for i in result.used_views],
            "rejected_views": [str(args.images[i]) for i in result.rejected_views]}


def _table(report: dict[str, Any]) -> str:
    lines = [f"status      {report['status']}"]
    if report["status"] != "ok":
        lines.append(f"reason      {report.get('reason', '')}")
    else:
        cam, sig = report["camera"], report["sigma"]
        sigma_f = sig.get("f", sig.get("fx", math.nan))
        spread = f"1-sigma {sigma_f:.2f} px" if math.isfinite(sigma_f) else "1-sigma not estimated"
        lines.append(f"focal       fx {cam['fx']:.2f} px, fy {cam['fy']:.2f} px ({spread})")
        lines.append(f"centre      cx {cam['cx']:.2f} px, cy {cam['cy']:.2f} px")
        lines.append("distortion  " + ", ".join(f"{k} {cam[k]:+.6g}" for k in ("k1", "k2", "k3", "p1", "p2")))
        lines.append(f"pruned      {', '.join(report['pruned']) or 'none'} (3-sigma rule)")
        lines.append(f"residual    {report['rms_px']:.3f} px rms")
    for item in report.get("images", []):
        lines.append(f"  {item['image']}: {item['status']}, {item['matches']} stars")
    return "\n".join(lines)


def _each_once(paths: list[str]) -> None:
    """Refuse an image given twice (the same file under any name): its stars would count twice
    in the fit and its sigmas come out too small by the square root of two."""
    seen: dict[Path, str] = {}
    for path in paths:
        key = Path(path).resolve()
        if key in seen:
            raise InvalidInputError(f"{path} is given twice (also as {seen[key]}): each image may count once in "
                                    "the fit")
        seen[key] = path


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    apply_max_pixels_option(args)
    _each_once(args.images)
    if args.square_mm is not None and not args.checkerboard:
        raise InvalidInputError("--square-mm is the size of a checkerboard's squares; give it with --checkerboard")
    report = _from_checkerboard(args) if args.checkerboard else _from_stars(args)
    if args.out and report["status"] == "ok":
        with atomic_path(args.out) as tmp:
            Path(tmp).write_text(json.dumps(report["camera"], indent=2))
    if args.json:
        print_json(report)
    else:
        print(_table(report))
    return 0 if report["status"] == "ok" else 1
