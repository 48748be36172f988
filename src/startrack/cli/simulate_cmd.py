"""startrack simulate: render star images of the Hipparcos sky with their truth.

One frame (--frames 1, the default) goes to the --out file: FITS (truth as header cards and a
TRUTH table) or a 16-bit PNG / TIFF with a <stem>.truth.json beside it; the folder must exist.
Several frames go to the --out folder (created if missing) as frame_00000.fits, ... (or
--format png / tif) with frames.csv, the index of the sequence; a progress bar is drawn on
standard error. The attitude (--ra-deg --dec-deg --roll-deg, or random from --seed) is that of
the middle of frame 0; the camera turns at --rate-deg-s (camera frame), or follows a recorded
--profile (CSV of t_s, qx, qy, qz, qw). Files are written atomically.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from ..errors import InvalidInputError
from ..io.truth_files import check_frame_path, index_row, truth_to_dict, write_frame, write_index
from ..simulate import ConstantRate, FrameTiming, load_profile, simulate_sequence
from .common import print_json
from .progress import ProgressBar
from .scene_options import (
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

exit status
  0 written; 2 misuse (bad option or output path), with one line
  'startrack simulate: error: ...' on standard error.
"""

SEQUENCE_FORMATS = {"fits": ".fits", "png": ".png", "tif": ".tif"}


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="startrack simulate", description=__doc__, epilog=OUTPUT_FORMATS,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_options(parser)
    add_render_options(parser)
    seq = parser.add_argument_group("sequence")
    seq.add_argument("--frames", type=int, default=1, metavar="N", help="number of frames (default 1)")
    seq.add_argument("--frame-rate-hz", type=float, metavar="F",
                     help="frames per second (default: back to back, 1 / exposure)")
    seq.add_argument("--profile", metavar="CSV", help="recorded attitude profile (t_s, qx, qy, qz, qw)")
    seq.add_argument("--format", choices=sorted(SEQUENCE_FORMATS), default="fits",
                     help="image format of a sequence's frames (default fits)")
    parser.add_argument("--out", help="output .fits, .png or .tif path for one frame (default startrack-sim.fits), "
                                      "a folder for several (default startrack-sim)")
    parser.add_argument("--json", action="store_true", help="print the truth as JSON")
    args = parser.parse_args(argv)
    if args.frames < 1:
        raise InvalidInputError(f"--frames must be a whole number >= 1, got {args.frames}")
    if args.frames == 1 and args.profile is None:
        return _one_frame(args)
    return _sequence(args)


def _one_frame(args: argparse.Namespace) -> int:
    out = Path(args.out or "startrack-sim.fits")
    check_frame_path(out)
    seed, sim = simulate_scene(args)
    written = write_frame(out, sim.image, sim.truth)
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
    if args.frame_rate_hz is not None and not (math.isfinite(args.frame_rate_hz) and args.frame_rate_hz > 0):
        raise InvalidInputError(f"--frame-rate-hz must be positive, got {args.frame_rate_hz:g}")
    rate_hz = args.frame_rate_hz if args.frame_rate_hz is not None else \
        1.0 / (sensor.exposure_s + (camera.height - 1) * line_time)
    profile, rot = _profile(args, rng, sensor.exposure_s + (camera.height - 1) * line_time)
    FrameTiming(line_time_s=line_time)  # checks --line-time-s before any file is written
    folder.mkdir(parents=True, exist_ok=True)
    frames = simulate_sequence(camera, profile, args.frames, frame_rate_hz=rate_hz, sensor=sensor,
                               max_mag=args.max_mag, catalog_epoch_jyear=scene_epoch(args), seed=seed,
                               noise=noise_model(args), sky_background=sky_background(args, rot),
                               line_time_s=line_time,
                               progress=None if args.json else ProgressBar("  frames"))
    rows = []
    for sim in frames:
        path = folder / f"frame_{sim.truth.frame_index:05d}{SEQUENCE_FORMATS[args.format]}"
        write_frame(path, sim.image, sim.truth)
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
