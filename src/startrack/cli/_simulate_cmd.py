"""startrack simulate: render star images of the Hipparcos sky with their truth.

One frame (--frames 1, the default) goes to the --out file: FITS (truth as header cards and a
TRUTH table) or a 16-bit PNG / TIFF with a <stem>.truth.json beside it; the folder must exist.
Several frames go to the --out folder (created if missing) as frame_00000.fits, ... (or
--format png / tif) with frames.csv, the index of the sequence; a progress bar is drawn on
standard error. The attitude (--ra-deg --dec-deg --roll-deg, or random from --seed) is that of
the middle of frame 0; the camera turns at --rate-deg-s (camera frame), or follows a recorded
--profile (CSV of t_s, qx, qy, qz, qw). Files are written atomically.

With --rig RIG.json (a startrack.CameraRig) one scene is rendered through every detector of the
rig into the --out folder: the attitude options give the body attitude, --rate-deg-s the body
rate (body frame), and the camera options are not used (the rig has the cameras). With --time the
Sun, the Moon and the Earth (seen from a dawn-dusk orbit at --altitude-km) blind the heads whose
exclusion cones they enter.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InvalidInputError
from ..frames import radec_roll_from_rotation
from ..io import (
    ENV_VAR,
    check_frame_path,
    fits_bytes,
    index_row,
    open_output,
    png_bytes,
    tiff_bytes,
    truth_to_dict,
    write_frame,
    write_index,
    write_output,
    write_with_sidecar,
)
from ..simulate import ConstantRate, FrameTiming, SplitFieldFrame, load_profile, simulate_sequence
from ._common import (
    add_max_pixels_option,
    check_finite_options,
    exit_status_epilog,
    max_pixels_option,
    non_empty,
    print_json,
    time_option,
)
from ._parser import CommandParser
from ._progress import ProgressBar
from ._render_limits import check_render_options
from ._scene_options import (
    add_render_options,
    add_scene_options,
    noise_model,
    render_sensor,
    scene_attitude,
    scene_camera,
    scene_epoch,
    scene_rate,
    scene_seed,
    simulate_scene,
    sky_background,
)

if TYPE_CHECKING:  # the rig modules are imported only by --rig
    from ..rig import CameraRig

RIG_ALTITUDE_KM = 500.0
"""--altitude-km when not given: a dawn-dusk orbit at 500 km (only with --rig --time)."""

OUTPUT_FORMATS = """\
output (text, the default)
  wrote FILES (one frame) or wrote N frames to FOLDER (a sequence)
  seed N; boresight RA .. deg, Dec .. deg, roll .. deg; K stars in the image

output (--json)
  One frame: one object: seed, files (the paths written), ra_deg, dec_deg, roll_deg (boresight at
  mid-exposure, ICRS, and the startrack.frames roll), qx, qy, qz, qw (rot_cam_from_icrs, scalar
  last), epoch_jyear, exposure_s, rate_deg_s, t_mid_s, time_mid, line_time_s, frame_index,
  camera {width, height, fx, fy, cx, cy, k1, k2, k3, p1, p2, fov_deg, name}, sensor {...},
  stars: a list of {hip, x, y, mag, electrons, x_start, y_start, x_end, y_end, b_v} for the stars
  centred in the image (0-based pixels at mid-exposure; start / end of the exposure), rsos and
  bright_bodies. The .truth.json sidecar holds the same without seed, files.
  A sequence: seed, folder, frames, index (frames.csv: frame, file, t_mid_s, time_mid, ra_deg,
  dec_deg, roll_deg, qx, qy, qz, qw, rate_x_deg_s, rate_y_deg_s, rate_z_deg_s, n_stars).

output with --rig (files in the --out folder, default startrack-rig-sim)
  DETECTOR.fits (or --format png / tif) for every detector, with its truth as for one frame; a
  split detector's sidecar DETECTOR.truth.json lists its stars {hip, x, y, mag, electrons, field}.
  HEAD.stars.csv: each head's true star positions (x, y, mag), ready for solve-rig HEAD=CSV.
  rig_truth.json (and --json): seed, files, qx, qy, qz, qw (rot_body_from_icrs, scalar last),
  ra_deg, dec_deg, roll_deg (body +z axis), rate_deg_s (body frame), epoch_jyear, time_utc, heads:
  {name: {detector, file, stars_csv, blinded_by, n_stars, qx, qy, qz, qw (its rot_cam_from_icrs)}}.

""" + exit_status_epilog("0 written; 2 misuse (bad option or output path), with one line 'startrack simulate: error: "
                         "...' on standard error;")

SEQUENCE_FORMATS = {"fits": ".fits", "png": ".png", "tif": ".tif"}


def main(argv: list[str]) -> int:
    parser = CommandParser(prog="startrack simulate", description=__doc__, epilog=OUTPUT_FORMATS,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_options(parser)
    add_render_options(parser)
    seq = parser.add_argument_group("sequence")
    seq.add_argument("--frames", type=int, default=1, metavar="N", help="number of frames (default 1)")
    seq.add_argument("--frame-rate-hz", type=float, metavar="F",
                     help="frames per second (default: back to back, 1 / exposure)")
    seq.add_argument("--profile", metavar="CSV", help="recorded attitude profile (t_s, qx, qy, qz, qw)")
    seq.add_argument("--format", choices=sorted(SEQUENCE_FORMATS),
                     help="image format of a sequence's frames (default fits)")
    parser.add_argument("--out", type=non_empty,
                        help="output .fits, .png or .tif path for one frame (default startrack-sim.fits), "
                             "a folder for several (default startrack-sim)")
    parser.add_argument("--json", action="store_true", help="print the truth as JSON")
    rig = parser.add_argument_group("camera rig")
    rig.add_argument("--rig", metavar="RIG.json", help="render every head of this rig (files in the --out folder)")
    rig.add_argument("--time", metavar="UTC", help="with --rig: time of the frame (ISO), for Sun / Moon / Earth "
                                                   "exclusion")
    rig.add_argument("--altitude-km", type=float, default=RIG_ALTITUDE_KM, help="with --time: dawn-dusk orbit altitude "
                                                                     "(default 500)")
    add_max_pixels_option(parser)
    args = parser.parse_args(argv)
    check_finite_options(args)
    time_option(args)
    if args.frames < 1:
        raise InvalidInputError(f"--frames must be a whole number >= 1, got {args.frames}")
    check_render_options(args)
    if args.rig is not None:
        return _rig_frame(args)
    _check_single_camera_options(args)
    _check_frame_rate(args, _frame_span_s(args))
    if args.frames == 1 and args.profile is None:
        return _one_frame(args)
    return _sequence(args)


def _check_single_camera_options(args: argparse.Namespace) -> None:
    """Refuse the options that only --rig or a sequence reads, given without them (they were
    ignored): --time and --altitude-km (a rig's exclusion), --format (a sequence's frames; one
    frame's format is its --out file's)."""
    if args.time is not None or args.altitude_km != RIG_ALTITUDE_KM:
        raise InvalidInputError("--time and --altitude-km place a --rig's frame for its Sun, Moon and Earth exclusion; "
                                "give --rig, or leave them out")
    if args.frames == 1 and args.profile is None and args.format is not None:
        raise InvalidInputError("--format sets the files of a sequence (--frames N); one frame is written in the "
                                "format of its --out name (.fits, .png or .tif)")


def _frame_span_s(args: argparse.Namespace) -> float:
    """How long one frame takes, s: the exposure plus the rolling-shutter read-out of its rows."""
    return render_sensor(args).exposure_s + (scene_camera(args).height - 1) * (args.line_time_s or 0.0)


def _check_frame_rate(args: argparse.Namespace, frame_span_s: float) -> None:
    """Refuse a --frame-rate-hz that is not positive or whose period is shorter than a frame, for one
    frame as for a sequence.

    Raises
    ------
    InvalidInputError
        Naming --frame-rate-hz, the value and what is valid.
    """
    rate = args.frame_rate_hz
    if rate is None:
        return
    if not (math.isfinite(rate) and rate > 0 and math.isfinite(1.0 / rate)):
        raise InvalidInputError(f"--frame-rate-hz must be a positive number of frames per second (with a finite "
                                f"period, 1 / F s), got {rate:g}")
    if frame_span_s * rate > 1.0 + 1e-9:
        raise InvalidInputError(f"--frame-rate-hz {rate:g}: a frame (the exposure plus any rolling-shutter read-out) "
                                f"takes {frame_span_s:g} s and does not fit in a frame period of {1.0 / rate:g} s; "
                                f"valid: at most {1.0 / frame_span_s:g} Hz, or a shorter --exposure-s or --line-time-s")


@contextmanager
def _new_folder(folder: Path) -> Iterator[None]:
    """Create ``folder`` (and its missing parents) for the block; if the block fails, remove the
    folders it created that are still empty (a failed command leaves no empty output folder)."""
    created = [p for p in (folder, *folder.parents) if not p.exists()]
    folder.mkdir(parents=True, exist_ok=True)
    try:
        yield
    except BaseException:
        for path in created:  # innermost first
            if path.is_dir() and not any(path.iterdir()):
                path.rmdir()
        raise


def _inputs(args: argparse.Namespace) -> list[str]:
    """The files the command reads, which no output may replace."""
    return [p for p in (args.profile, args.rig) if p is not None]


def _one_frame(args: argparse.Namespace) -> int:
    out = Path(args.out or "startrack-sim.fits")
    check_frame_path(out, inputs=_inputs(args))
    seed, sim = simulate_scene(args)
    written = write_frame(out, sim.image, sim.truth, inputs=_inputs(args))
    truth = truth_to_dict(sim.truth)
    if args.json:
        print_json({"seed": seed, "files": [str(p) for p in written], **truth})
    else:
        print(f"wrote {', '.join(str(p) for p in written)}")
        print(f"seed {seed}; boresight RA {truth['ra_deg']:.5f} deg, Dec {truth['dec_deg']:+.5f} deg, "
              f"roll {truth['roll_deg']:.4f} deg; {len(truth['stars'])} stars in the image")
    return 0


def _sequence(args: argparse.Namespace) -> int:
    folder = Path(args.out or "startrack-sim")
    if folder.suffix.lower() in {".fits", ".fit", ".fts", ".png", ".tif", ".tiff"} or folder.is_file():
        raise InvalidInputError(f"--out {folder}: several frames (or --profile) need a folder, not a file")
    seed = scene_seed(args)
    camera, sensor = scene_camera(args), render_sensor(args)
    rng = np.random.default_rng(seed)
    line_time = args.line_time_s or 0.0
    span_s = sensor.exposure_s + (camera.height - 1) * line_time
    rate_hz = args.frame_rate_hz if args.frame_rate_hz is not None else 1.0 / span_s
    profile, rot = _profile(args, rng, span_s)
    FrameTiming(line_time_s=line_time)  # checks --line-time-s before any file is written
    frames = simulate_sequence(camera, profile, args.frames, frame_rate_hz=rate_hz, sensor=sensor,
                               max_mag=args.max_mag, catalog_epoch_jyear=scene_epoch(args), seed=seed,
                               noise=noise_model(args), sky_background=sky_background(args, rot),
                               line_time_s=line_time,
                               progress=None if args.json else ProgressBar("  frames"))
    first = next(frames)  # the sequence's own checks run here, before the folder is made
    rows = []
    with _new_folder(folder):
        for sim in itertools.chain([first], frames):
            path = folder / f"frame_{sim.truth.frame_index:05d}{SEQUENCE_FORMATS[args.format or 'fits']}"
            write_frame(path, sim.image, sim.truth, inputs=_inputs(args))
            rows.append(index_row(sim.truth, path))
        index = write_index(folder / "frames.csv", rows)
    if args.json:
        print_json({"seed": seed, "folder": str(folder), "frames": len(rows), "index": str(index)})
    else:
        print(f"wrote {len(rows)} frames to {folder} (index {index.name}); seed {seed}")
    return 0


def _profile(args: argparse.Namespace, rng: np.random.Generator, frame_span_s: float):
    """The attitude profile of a sequence and the attitude of frame 0's middle."""
    if args.profile is not None:
        if args.rate_deg_s is not None or args.ra_deg is not None:
            raise InvalidInputError("--profile gives the attitude and rate; leave out --ra-deg/--dec-deg "
                                    "and --rate-deg-s")
        profile = load_profile(args.profile)
        return profile, profile.attitudes([0.5 * frame_span_s])[0]
    rot = scene_attitude(args, rng)
    rate = scene_rate(args)
    return ConstantRate(rot, np.zeros(3) if rate is None else rate, t_ref_s=0.5 * frame_span_s), rot


def _rig_frame(args: argparse.Namespace) -> int:
    """--rig: one scene through every detector of the rig (see the epilog)."""
    from astropy.time import Time

    from ..multihead import dawn_dusk_bodies
    from ..rig import CameraRig
    from ..simulate import simulate_rig

    given = [o for o, v in (("--camera", args.camera), ("--fov-deg", args.fov_deg), ("--width", args.width),
                            ("--height", args.height), ("--profile", args.profile)) if v is not None]
    if given or args.frames != 1:
        leave_out = ", ".join(given) or "--frames"
        raise InvalidInputError(f"--rig has its cameras and renders one frame; leave out {leave_out}")
    rig = CameraRig.load(args.rig)
    _check_rig_sizes(args, rig)
    _check_frame_rate(args, render_sensor(args).exposure_s)  # one frame: no rolling shutter
    folder = Path(args.out or "startrack-rig-sim")
    if folder.suffix.lower() in SEQUENCE_FORMATS.values() or folder.is_file():
        raise InvalidInputError(f"--out {folder}: --rig writes a folder, not a file")
    seed = scene_seed(args)
    rng = np.random.default_rng(seed)
    rot, rate = scene_attitude(args, rng), scene_rate(args)
    bodies = None if args.time is None else dawn_dusk_bodies(args.time, args.altitude_km)
    time = None if args.time is None else Time(args.time, scale="utc")
    frame = simulate_rig(rig, rot, rate_body_rad_s=rate, sensor=render_sensor(args), max_mag=args.max_mag,
                         epoch_jyear=scene_epoch(args), rng=rng, noise=noise_model(args), time=time, bodies=bodies)
    with _new_folder(folder):
        report = _write_rig(folder, rig, frame, args.format or "fits", seed, rate, scene_epoch(args), time)
    if args.json:
        print_json(report)
    else:
        blinded = [f"{h} by the {b}" for h, b in frame.blinded_by.items() if b]
        print(f"wrote {len(report['files'])} files to {folder}; seed {seed}; body RA {report['ra_deg']:.5f} deg, "
              f"Dec {report['dec_deg']:+.5f} deg, roll {report['roll_deg']:.4f} deg"
              + (f"; blinded: {', '.join(blinded)}" if blinded else ""))
    return 0


def _check_rig_sizes(args: argparse.Namespace, rig: CameraRig) -> None:
    """Refuse a rig camera whose image is over the --max-pixels limit, before anything is rendered.

    Raises
    ------
    InvalidInputError
        Naming the rig file, the head, its camera width and height, the limit and how to raise it.
    """
    limit = max_pixels_option(args)
    for head in rig:
        width, height = head.camera.width, head.camera.height
        if width * height > limit:
            raise InvalidInputError(f"rig file {args.rig}: head {head.name!r}: camera width {width} x height {height} "
                                    f"is {width * height:,} px, over the limit of {limit:,} px; raise it with "
                                    f"--max-pixels (or {ENV_VAR}) if you mean it")


def _quat(rot) -> dict[str, float]:
    return dict(zip(("qx", "qy", "qz", "qw"), (float(v) for v in rot.as_quat(canonical=True)), strict=True))


def _write_rig(folder: Path, rig, frame, fmt: str, seed: int, rate, epoch: float, time) -> dict:
    """Every detector's image and truth, each head's star CSV and rig_truth.json; the report."""
    files, heads = [], {}
    for det, sim in frame.frames.items():
        path = folder / f"{det}{SEQUENCE_FORMATS[fmt]}"
        files += _write_detector(path, sim)
        for head in rig.detectors[det]:
            csv_path = folder / f"{head.name}.stars.csv"
            n = _write_stars_csv(csv_path, sim, head.name)
            files.append(csv_path)
            heads[head.name] = {"detector": det, "file": path.name, "stars_csv": csv_path.name,
                                "blinded_by": frame.blinded_by[head.name], "n_stars": n,
                                **_quat(head.rot_cam_from_icrs(frame.rot_body_from_icrs))}
    ra, dec, roll = (math.degrees(float(a)) for a in radec_roll_from_rotation(frame.rot_body_from_icrs))
    report = {"seed": seed, **_quat(frame.rot_body_from_icrs), "ra_deg": ra, "dec_deg": dec, "roll_deg": roll,
              "rate_deg_s": [0.0, 0.0, 0.0] if rate is None else [math.degrees(v) for v in rate],
              "epoch_jyear": epoch, "time_utc": None if time is None else time.utc.isot, "heads": heads}
    truth_path = folder / "rig_truth.json"
    write_output(truth_path, json.dumps(report, indent=1, allow_nan=False))
    return {**report, "files": [str(p) for p in [*files, truth_path]]}


def _write_detector(path: Path, sim) -> list[Path]:
    """One detector's image with its truth (a split detector's truth as a JSON sidecar, written with
    the image as one group: both files or neither)."""
    if not isinstance(sim, SplitFieldFrame):
        return write_frame(path, sim.image, sim.truth)
    if path.suffix == ".fits":
        blob = fits_bytes(sim.image)
    else:
        image = np.clip(np.round(sim.image), 0, 65535).astype(np.uint16)
        blob = png_bytes(image) if path.suffix == ".png" else tiff_bytes(image)
    t = sim.truth
    stars = [{"hip": int(t.ids[i]), "x": float(t.x[i]), "y": float(t.y[i]), "mag": float(t.mag[i]),
              "electrons": float(t.electrons[i]), "field": str(t.field[i])} for i in range(len(t))]
    return write_with_sidecar(path, blob, json.dumps({"detector": t.detector, "stars": stars}, indent=1))


def _write_stars_csv(path: Path, sim, head: str) -> int:
    """The head's stars inside its image (x, y, mag) as CSV; how many."""
    t = sim.truth
    if isinstance(sim, SplitFieldFrame):
        height, width = sim.image.shape
        keep = (t.field == head) & (t.x >= -0.5) & (t.y >= -0.5) & (t.x <= width - 0.5) & (t.y <= height - 0.5)
    else:
        keep = t.inside()
    with open_output(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["x", "y", "mag"])
        writer.writerows(zip(t.x[keep].tolist(), t.y[keep].tolist(), t.mag[keep].tolist(), strict=True))
    return int(np.count_nonzero(keep))
