"""startrack track FOLDER: follow the attitude over a sequence of images (FITS, PNG, JPEG, TIFF
files in a folder, taken in name order): lost-in-space on the first frame, then tracking from
frame to frame, back to lost-in-space when tracking fails. Writes one CSV row per frame."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InvalidInputError
from ..io.track_csv import COLUMNS, track_row, write_track_csv
from ..track import Tracker
from .common import add_epoch_option, add_fov_options, epoch_option, fov_kwargs
from .progress import ProgressBar, ensure_database_for

IMAGE_SUFFIXES = {".fits", ".fit", ".fts", ".png", ".jpg", ".jpeg", ".tif", ".tiff"}

EPILOG = "CSV columns: " + ", ".join(COLUMNS) + (
    ".\nmode is lost-in-space or tracking; status is ok, too_few_stars, no_match or timeout; the quaternion "
    "(qw >= 0) is rot_cam_from_icrs; the rate is the camera's, in the camera frame.\n"
    "Exit status: 0 when every frame has an attitude, 1 when some have none, 2 on bad input.")


def _frames(source: Path) -> list[Path]:
    if source.is_file():
        return [source]
    if not source.is_dir():
        raise InvalidInputError(f"{source}: no such file or folder")
    files = sorted(p for p in source.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    if not files:
        raise InvalidInputError(f"{source}: no image files (valid: {', '.join(sorted(IMAGE_SUFFIXES))})")
    return files


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="startrack track", description=__doc__, epilog=EPILOG,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", help="a folder of images (name order = time order) or one image")
    add_fov_options(parser)
    parser.add_argument("--frame-interval-s", type=float, default=0.1, help="time between frames (default 0.1 s)")
    parser.add_argument("--out", default="track.csv", help="CSV file to write (default track.csv)")
    add_epoch_option(parser)
    args = parser.parse_args(argv)
    if not args.frame_interval_s > 0:
        raise InvalidInputError(f"--frame-interval-s must be positive, got {args.frame_interval_s:g}")
    files = _frames(Path(args.source))
    options = fov_kwargs(args)
    tracker = _tracker(files[0], options, epoch_option(args))
    ensure_database_for(options["fov_deg"], options["fov_range_deg"], options["camera"])
    bar = ProgressBar("  frames")
    rows, solved = [], 0
    for k, path in enumerate(files):
        step = tracker.update_image(path, k * args.frame_interval_s)
        rows.append(track_row(k, path.name, step))
        solved += bool(step.status)
        bar(k + 1, len(files))
    write_track_csv(args.out, rows)
    print(f"{solved} of {len(files)} frames have an attitude; wrote {args.out}")
    return 0 if solved == len(files) else 1


def _tracker(first: Path, options: dict, epoch) -> Tracker:
    from ..io import read_image

    if options["camera"] is not None:
        return Tracker(camera=options["camera"], epoch=epoch)
    height, width = read_image(first).data.shape
    return Tracker(width=width, height=height, fov_deg=options["fov_deg"], fov_range_deg=options["fov_range_deg"],
                   epoch=epoch)
