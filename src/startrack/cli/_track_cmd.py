"""startrack track FOLDER: follow the attitude over a sequence of images (FITS, PNG, JPEG, TIFF
files in a folder, taken in name order): lost-in-space on the first frame, then tracking from
frame to frame, back to lost-in-space when tracking fails. Writes one CSV row per frame.

A frame that cannot be used (an unreadable or corrupt file, a size other than the sequence's)
gets a row with status "error" and the reason, and the run goes on. The rows are written as the
frames are processed to a temporary file that replaces --out at the end (--out - writes them to
standard output as they come); an interrupted run leaves the previous CSV as it was."""

from __future__ import annotations

import argparse
import io
import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InvalidInputError, StartrackError, require
from ..io import (
    COLUMNS,
    IMAGE_SUFFIXES,
    STDOUT,
    error_row,
    in_name_order,
    max_pixels_limit,
    output_target,
    read_image,
    track_csv_writer,
    track_row,
)
from ..track import Tracker
from ._common import (
    add_epoch_option,
    add_fov_options,
    add_max_pixels_option,
    check_time_option,
    epoch_option,
    exit_status_epilog,
    fov_kwargs,
    max_pixels_option,
    non_empty,
)
from ._parser import CommandParser
from ._progress import ProgressBar, ensure_database_for

EPILOG = "CSV columns: " + ", ".join(COLUMNS) + (
    ".\nmode is lost-in-space, tracking, streak lost-in-space, streak tracking (a smeared frame solved from its "
    "streaks, with an exposure time), or none for a frame that could not be used; status is ok, "
    "too_few_stars, no_match, timeout, or error (an unreadable frame or one of another size; the reason "
    "says which); the quaternion (qw >= 0) is rot_cam_from_icrs; the rate is the camera's, in the camera "
    "frame.\n\n") + exit_status_epilog(
    "0 every frame has an attitude; 1 some have none (the status and reason columns say why); 2 misuse (a bad "
    "option, no images, an --out that cannot be written), with one line 'startrack track: error: ...' on standard "
    "error;")


def _frames(source: Path) -> list[Path]:
    if source.is_file():
        return [source]
    if not source.is_dir():
        raise InvalidInputError(f"{source}: no such file or folder")
    files = in_name_order([p for p in source.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES])
    if not files:
        raise InvalidInputError(f"{source}: no image files (valid: {', '.join(sorted(IMAGE_SUFFIXES))})")
    return files


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack track", description=__doc__, epilog=EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("source", help="a folder of images (name order = time order, numbers in names compared as "
                                       "numbers: frame_2 before frame_10) or one image")
    add_fov_options(parser)
    parser.add_argument("--frame-interval-s", type=float, default=0.1, help="time between frames (default 0.1 s)")
    parser.add_argument("--exposure-s", type=float, default=None, metavar="T",
                        help="exposure of every frame (s; default: the header's EXPTIME, EXPOSURE or ExposureTime); "
                             "with one, the tracker switches between point and streak mode by the smear and prints "
                             "the smear limits and where it switched")
    parser.add_argument("--out", default="track.csv", type=non_empty,
                        help="CSV file to write (default track.csv; - for standard output)")
    add_epoch_option(parser)
    add_max_pixels_option(parser)
    return parser


@dataclass
class _Sequence:
    """The tracker of a sequence, made from its first readable frame (or the camera)."""

    options: dict
    epoch: float | None
    exposure_s: float | None = None
    tracker: Tracker | None = None
    size: tuple[int, int] | None = None
    first: str = ""
    unusable: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    limits_told: bool = False

    def __post_init__(self) -> None:
        camera = self.options["camera"]
        if camera is not None:
            self.tracker = Tracker(camera=camera, epoch=self.epoch)
            self.size, self.first = (camera.width, camera.height), f"camera {camera.name or 'given'}"

    def row(self, k: int, path: Path, t_s: float) -> list[str]:
        """The CSV row of frame ``k``: its tracking step, or an error row naming the problem."""
        from ..rate import header_exposure_s

        try:
            img = read_image(path)
            self._check_size(img.data.shape[1], img.data.shape[0], path)
            exposure = self.exposure_s if self.exposure_s is not None else header_exposure_s(img.header)
            step = self._tracker.update_image(img.data, t_s, streak_exposure_s=exposure)
        except (StartrackError, ValueError) as exc:
            self.unusable.append(path.name)
            return error_row(k, path.name, t_s, str(exc))
        self._note(k, path.name, step, exposure)
        return track_row(k, path.name, step)

    def _note(self, k: int, name: str, step, exposure: float | None) -> None:
        """Remember the smear limits (once, at the first frame with an exposure) and each mode switch."""
        if exposure is None:
            return
        if not self.limits_told:
            self.notes.append(self._tracker.smear_limits(exposure, *self._size).describe())
            self.limits_told = True
        if step.extra.get("switched"):
            other = "streak" if self._tracker.mode == "point" else "point"
            self.notes.append(f"frame {k} ({name}, t = {step.t_s:g} s): {other} -> {self._tracker.mode} mode "
                              f"(smear {step.extra['streak_px']:.6g} px)")

    @property
    def _tracker(self) -> Tracker:
        """The tracker, made by ``__post_init__`` (a camera given) or by the first readable frame."""
        return require(self.tracker, "the sequence's tracker")

    @property
    def _size(self) -> tuple[int, int]:
        return require(self.size, "the sequence's frame size")

    def _check_size(self, width: int, height: int, path: Path) -> None:
        if self.size is None:
            self.size, self.first = (width, height), path.name
            self.tracker = Tracker(width=width, height=height, fov_deg=self.options["fov_deg"],
                                   fov_range_deg=self.options["fov_range_deg"], epoch=self.epoch)
        elif (width, height) != self.size:
            raise InvalidInputError(
                f"{path.name}: frame is {width} x {height} px but the sequence's frames are "
                f"{self.size[0]} x {self.size[1]} px (from {self.first}); every frame must have one size")


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    epoch = epoch_option(args)
    if not (math.isfinite(args.frame_interval_s) and args.frame_interval_s > 0):
        raise InvalidInputError(f"--frame-interval-s must be a positive, finite number of seconds, "
                                f"got {args.frame_interval_s:g}")
    files = _frames(Path(args.source))
    output_target(args.out, files)  # refused before any work: an input frame, a folder, ...
    options = fov_kwargs(args)
    with max_pixels_limit(max_pixels_option(args)):
        ensure_database_for(options["fov_deg"], options["fov_range_deg"], options["camera"])
        sequence, solved = _Sequence(options, epoch, _exposure_option(args.exposure_s)), 0
        bar = ProgressBar("  frames")
        try:
            with track_csv_writer(args.out, inputs=files) as write:
                for k, path in enumerate(files):
                    row = sequence.row(k, path, k * args.frame_interval_s)
                    write(row)
                    solved += row[COLUMNS.index("status")] == "ok"
                    bar(k + 1, len(files))
        finally:
            bar.close()
    _summary(solved, len(files), sequence.unusable, args.out, sequence.notes)
    return 0 if solved == len(files) else 1


def _exposure_option(exposure_s: float | None) -> float | None:
    """--exposure-s when it is given, checked against :data:`._common.EXPOSURE_RANGE_S`, else None."""
    return None if exposure_s is None else check_time_option(exposure_s, "--exposure-s", "")


def _is_stdout(out: str) -> bool:
    """True when --out is standard output (``-``, or a name of the same file such as /dev/stdout)."""
    if out == STDOUT:
        return True
    try:
        return os.path.samestat(os.stat(out), os.fstat(sys.stdout.fileno()))
    except (OSError, ValueError, io.UnsupportedOperation):
        return False


def _summary(solved: int, total: int, unusable: list[str], out: str, notes: list[str]) -> None:
    """The smear limits and mode switches, then the one-line summary, on standard error when the
    CSV went to standard output."""
    to_stdout = _is_stdout(out)
    for note in notes:
        print(note, file=sys.stderr if to_stdout else sys.stdout)
    where = "standard output" if out == STDOUT else out
    text = f"{solved} of {total} frames have an attitude"
    if unusable:
        names = ", ".join(unusable[:3]) + (", ..." if len(unusable) > 3 else "")
        text += f"; {len(unusable)} could not be used ({names}: see the reason column)"
    print(f"{text}; wrote {where}", file=sys.stderr if to_stdout else sys.stdout)
