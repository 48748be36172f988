"""Pieces the solving subcommands share: FOV and epoch options, the output formats, exit codes.

Exit status of every subcommand: 0 solved (or written), 1 an expected failure (not solved: the
status and reason are printed), 2 misuse (a bad option, an unreadable file, an invalid image or
star list), reported as one line ``startrack <cmd>: error: ...`` on standard error, 3 an
unexpected error, a fault of startrack's, reported as one line naming the exception's type
(:data:`startrack.cli._main.DEBUG_ENV` set to 1 shows its traceback instead). Each subcommand's
``--help`` says so with :data:`FAULT_EXIT_STATUS` (:func:`exit_status_epilog`).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import textwrap
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..camera import Camera, get_preset
from ..catalog import constellation_of
from ..errors import InvalidInputError, require
from ..identify import MATCHERS
from ..io import solution_to_dict, streak_fields
from ..results import AttitudeSolution, Detections
from ..solve import (
    DEFAULT_FOV_RANGE_DEG,
    MAX_FOV_DEG,
    MIN_FOV_DEG,
    WIDE_RETRY_FOV_RANGE_DEG,
    check_fov_deg,
    epoch_jyear,
)
from ._main import DEBUG_ENV, INTERNAL_ERROR

if TYPE_CHECKING:  # the reader's module (Pillow and the rest) loads only for the commands that read images
    from ..io import Image

FAULT_EXIT_STATUS = (f"{INTERNAL_ERROR} an unexpected error, a fault of startrack's (please report it), with one "
                     f"line naming the exception's type on standard error ({DEBUG_ENV}=1 shows its traceback).")
"""Exit status 3 as every subcommand's ``--help`` states it, after the statuses 0 to 2 of the
command (:func:`exit_status_epilog`); :func:`startrack.cli._main.main` returns it."""

HELP_WIDTH = 100
"""Width the ``--help`` epilogs are wrapped at, characters."""

_UNBROKEN = re.compile(r"(?:^|(?<=[;:] ))\d \S+|'startrack [^']*'")
"""What :func:`wrap_help` keeps on one line: an exit status and its first word, a quoted message."""


def wrap_help(text: str) -> str:
    """``text`` as lines of a ``--help`` epilog: two spaces in, wrapped at :data:`HELP_WIDTH`.

    Parameters
    ----------
    text : str
        One paragraph; its line breaks and runs of spaces count as one space.

    Returns
    -------
    str
        The wrapped lines, ending with a newline: words are never split (at hyphens neither), nor
        an exit status from its first word ("3 an") or a quoted ``'startrack <cmd>: error: ...'``.
    """
    glued = _UNBROKEN.sub(lambda m: m[0].replace(" ", "\0"), " ".join(text.split()))
    return textwrap.fill(glued, width=HELP_WIDTH, initial_indent="  ", subsequent_indent="  ",
                         break_long_words=False, break_on_hyphens=False).replace("\0", " ") + "\n"


def exit_status_epilog(statuses: str, note: str = "") -> str:
    """The "exit status" paragraph of a subcommand's ``--help``.

    Parameters
    ----------
    statuses : str
        The statuses 0 to 2 the command returns, separated and ended by ';'
        (e.g. ``"0 solved; 1 not solved; 2 misuse ...;"``).
    note : str, optional
        A sentence after the statuses.

    Returns
    -------
    str
        ``exit status`` and, under it (:func:`wrap_help`), ``statuses``, :data:`FAULT_EXIT_STATUS`
        and ``note``; ending with a newline.
    """
    return "exit status\n" + wrap_help(f"{statuses} {FAULT_EXIT_STATUS} {note}")


FOV_SOURCE_WORDS = {"given": "the field or range given", "camera": "the camera's",
                    "header": "found from the field the image's header states",
                    "default": "found in the default search, {:g}-{:g} deg".format(*DEFAULT_FOV_RANGE_DEG),
                    "wide": "found in the search of {:g}-{:g} deg".format(*WIDE_RETRY_FOV_RANGE_DEG)}
"""How the table's FOV row names :attr:`startrack.results.AttitudeSolution.fov_source`."""

SOLUTION_FORMATS = """\
output (table, the default)
  status       solved, or the status of a failure (too_few_stars, no_match, timeout)
  RA, Dec      boresight in ICRS, deg, and the IAU constellation it lies in
  roll         deg, the startrack.frames definition (equal to tetra3 / cedar-solve roll): the
               image's top (row 0) points 360 - roll deg east of north
  FOV          horizontal field of view, deg, the focal length, px, the pixel scale at the
               image's centre, arcsec/px, and where the search for it started: the field
               given, the camera's, the field the header states (EXIF focal length, a FITS
               WCS's scale, FOCALLEN and XPIXSZ), the default search (3-100 deg) or the
               search of 90-150 deg after the default found nothing
  parity       (only for a mirror image of the sky: a star diagonal, a flipped file) mirrored
  stars        stars matched (of those detected, for an image; with --guided, how many of them
               were measured where the solution predicts them)
  residual     rms angle between matched stars and the catalog after the fit, arcsec
  1-sigma      attitude uncertainty across the boresight and about it (roll), arcsec
  false match  upper bound on the probability that the identification is wrong
  epoch        the catalog epoch the stars were taken at (Julian year) and where it came
               from: given (--epoch), a header card (CATEPOCH, DATE-OBS, MJD-OBS,
               DateTimeOriginal) or default (J2000.0, nothing said when)
  time         solve time (detection and identification), ms
  qx qy qz qw  the quaternion of rot_cam_from_icrs, scalar last
  alt, az      (with a ground site) apparent altitude and azimuth of the boresight, deg
  When not solved: status, reason, (stars detected) and time.

output (--json)
  One object. Always: status ("ok", "too_few_stars", "no_match", "timeout"), reason (empty
  when solved), solve_time_s, and for an image n_detections. When solved also: ra_deg,
  dec_deg, constellation (as the table's), roll_deg, fov_deg, qx, qy, qz, qw, focal_px,
  pixel_scale_arcsec (at the image's centre), mirrored (true for a mirror image: its camera's
  pixel x runs against the camera frame's x axis), sigma_cross_boresight_arcsec,
  sigma_roll_arcsec, residual_rms_arcsec, false_match_prob, guided_stars (how many of the
  matches were measured where the solution predicts them: solve --guided; they are the last
  matches and detections), epoch_jyear and epoch_source (as the table's epoch), fov_source
  (given, camera, header, default or wide: as the table's FOV), and matches: a list of
  {index, hip, residual_arcsec[, x, y]} (index into the detections or star list; x, y in
  0-based pixels). Values that are undefined are null. With a ground site (solve --site or
  --latitude-deg / --longitude-deg) also: time_utc, site, latitude_deg, longitude_deg,
  altitude_deg, azimuth_deg.

""" + exit_status_epilog("0 solved; 1 not solved (the reason is printed); 2 misuse (bad option, unreadable file or "
                         "invalid input), with one line 'startrack <cmd>: error: ...' on standard error;")


def add_fov_options(parser: argparse.ArgumentParser) -> None:
    """--fov-deg, --fov-range-deg, --camera (mutually exclusive)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--fov-deg", type=float, metavar="F",
                       help=f"horizontal field of view in deg ({MIN_FOV_DEG:g} to {MAX_FOV_DEG:g}), trusted to +-3 %%")
    group.add_argument("--fov-range-deg", type=float, nargs=2, metavar=("LO", "HI"),
                       help="range of horizontal fields of view to search, deg (default 3 100, the default "
                            "database's range)")
    group.add_argument("--camera", metavar="PRESET", type=non_empty,
                       help="a calibrated camera preset (fixes the focal length)")


def add_method_option(parser: argparse.ArgumentParser) -> None:
    """--method: the lost-in-space matcher (the overlay needs a prior, so it is Python-only)."""
    names = [name for name in MATCHERS if name != "overlay"]
    parser.add_argument("--method", choices=names, default="quads",
                        help="star-identification matcher (default quads; the others need --fov-deg or --camera); "
                             "see docs/identification.md")


def add_timeout_option(parser: argparse.ArgumentParser) -> None:
    """--timeout-s: the lost-in-space search's time limit (the matcher's option ``timeout_s``)."""
    parser.add_argument("--timeout-s", type=float, metavar="S",
                        help="give up the lost-in-space search after S seconds of wall time (default 5; raise it "
                             "on a slow or busy machine, or for lists full of spots that are not stars)")


def method_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """``method`` (and ``options`` when --timeout-s is given) for solve_image / solve_stars.

    Raises
    ------
    InvalidInputError
        A --timeout-s that is not a positive finite number of seconds; a --method other than quads
        with no field of view to go by, or with a range of pixel aspects (said in the options'
        words, before the solver says it in its arguments').
    """
    _check_method_needs(args)
    if getattr(args, "timeout_s", None) is None:
        return {"method": args.method}
    from ..identify import options_for

    if not args.timeout_s > 0:  # NaN and infinities are refused with every float option
        raise InvalidInputError(f"--timeout-s must be a positive number of seconds, got {args.timeout_s:g}")
    return {"method": args.method, "options": options_for(args.method, timeout_s=args.timeout_s)}


def _check_method_needs(args: argparse.Namespace) -> None:
    """The matchers other than quads take a field of view known to a few per cent and one pixel
    aspect (:mod:`startrack.identify._registry`)."""
    method = getattr(args, "method", "quads")
    if method == "quads":
        return
    if all(getattr(args, key, None) is None for key in ("fov_deg", "fov_range_deg", "camera")):
        raise InvalidInputError(f"--method {method} needs the field of view to within 5 %: give --fov-deg or "
                                "--camera, or leave --method out (quads searches a range of fields)")
    if len(getattr(args, "pixel_aspect", None) or ()) == 2:
        raise InvalidInputError(f"--method {method} needs one pixel aspect: give --pixel-aspect one number, or "
                                "leave --method out (quads searches a range)")


def add_epoch_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--epoch", type=float, metavar="YEAR",
                        help="catalog epoch as a Julian year, e.g. 2025.5 (default 2000.0)")


def fov_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments ``fov_deg, fov_range_deg, camera`` for the solvers, checked.

    Raises
    ------
    InvalidInputError
        Naming the option: a FOV outside MIN_FOV_DEG..MAX_FOV_DEG (0.5..150 deg) or not a number, LO > HI,
        an unknown preset.
    """
    camera: Camera | None = get_preset(args.camera) if args.camera else None
    if args.fov_deg is not None:
        check_fov_deg(args.fov_deg, "--fov-deg")
    fov_range = None
    if args.fov_range_deg:
        lo, hi = (check_fov_deg(v, "--fov-range-deg") for v in args.fov_range_deg)
        if lo > hi:
            raise InvalidInputError(f"--fov-range-deg LO HI needs LO <= HI, got {lo:g} {hi:g}")
        fov_range = (lo, hi)
    return {"fov_deg": args.fov_deg, "fov_range_deg": fov_range, "camera": camera}


def epoch_option(args: argparse.Namespace) -> float | None:
    """The checked --epoch (Julian year) or None.

    Every command that takes --epoch calls this before any work, so it also refuses what no
    option of such a command may be: a NaN or infinite number in any float option
    (:func:`check_finite_options`) and a --time that is not a time (:func:`time_option`).
    """
    check_finite_options(args)
    time_option(args)
    if args.epoch is None:
        return None
    try:
        return epoch_jyear(args.epoch)
    except InvalidInputError:
        raise InvalidInputError(f"--epoch must be a Julian year such as 2025.5, got {args.epoch:g}") from None


EXPOSURE_RANGE_S = (1e-4, 3600.0)
"""Valid exposure times and frame intervals (--exposure-s, |--dt-s|), s: 0.1 ms to an hour."""


def check_time_option(value: float | None, option: str, what: str, *, signed: bool = False) -> float:
    """``value`` if it is a time within :data:`EXPOSURE_RANGE_S` (in magnitude when ``signed``), else
    an InvalidInputError naming ``option`` and the valid range."""
    lo, hi = EXPOSURE_RANGE_S
    valid = f"{lo:g} to {hi:g} s" + (f", or -{hi:g} to -{lo:g} s" if signed else "")
    if value is None:
        raise InvalidInputError(f"{what} needs {option} ({valid})")
    if not lo <= (abs(value) if signed else value) <= hi:
        raise InvalidInputError(f"{option} must be {valid}, got {value:g}")
    return value


def _option_name(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def _floats(value: Any) -> list[float]:
    if isinstance(value, float):
        return [value]
    if isinstance(value, list | tuple):
        return [v for v in value if isinstance(v, float)]
    return []


def check_finite_options(args: argparse.Namespace) -> None:
    """Refuse NaN or an infinity given to any float option of a parsed command line.

    Raises
    ------
    InvalidInputError
        Naming the first such option (e.g. ``--max-mag must be a finite number, got nan``).
    """
    for dest, value in sorted(vars(args).items()):
        bad = [v for v in _floats(value) if not np.isfinite(v)]
        if bad:
            raise InvalidInputError(f"{_option_name(dest)} must be a finite number, got {bad[0]:g}")


def parse_utc_time(text: str, option: str = "--time"):
    """An ISO 8601 UTC time (``2024-08-12T03:15:00``, a date, or ``2024-08-12 03:15:00``) as an
    astropy Time; InvalidInputError naming ``option`` otherwise."""
    from astropy.time import Time

    try:
        when = Time(str(text).strip(), scale="utc")
    except (ValueError, TypeError):
        when = None
    if when is None or not when.isscalar or not np.isfinite(when.jd):
        raise InvalidInputError(f"{option} must be an ISO 8601 UTC time such as 2024-08-12T03:15:00, got {text!r}")
    return when


def time_option(args: argparse.Namespace):
    """The parsed --time of a command (an astropy Time), None when it has none or it is not given."""
    text = getattr(args, "time", None)
    return None if text is None else parse_utc_time(text, "--time")


def add_max_pixels_option(parser: argparse.ArgumentParser) -> None:
    """--max-pixels: the size limit of the images read (or rendered), see startrack.io._limits."""
    from ..io import DEFAULT_MAX_PIXELS, ENV_VAR

    parser.add_argument("--max-pixels", type=positive_count, metavar="N",
                        help=f"largest image accepted, width x height in pixels (default {DEFAULT_MAX_PIXELS:,}, "
                             f"or ${ENV_VAR}); checked from the file header before decoding")


def max_pixels_option(args: argparse.Namespace) -> int:
    """The limit --max-pixels gives (or the one in force without it)."""
    from ..io import resolve_max_pixels

    return resolve_max_pixels(getattr(args, "max_pixels", None))


def apply_max_pixels_option(args: argparse.Namespace) -> None:
    """Make --max-pixels the limit of every image the rest of the command reads (the command's
    context, :func:`startrack.cli._run_context.command_context`, undoes it when the command ends)."""
    from ..io import set_max_pixels

    set_max_pixels(getattr(args, "max_pixels", None))


def check_output_folder(folder: str | Path, option: str = "--out") -> None:
    """Refuse an output folder (created if missing) that is an existing file, naming ``option``."""
    if Path(folder).exists() and not Path(folder).is_dir():
        raise InvalidInputError(f"{option} {folder} is a file; give a folder (it is created if missing)")


def announce_mosaic(image: Image) -> None:
    """Say on standard error that ``image`` was a colour-filter mosaic read at full resolution
    (:mod:`startrack.io._mosaic`); nothing for any other image."""
    if image.mosaic is None:
        return
    from ..io import describe_mosaic

    sys.stderr.write(f"{image.path}: {describe_mosaic(image.mosaic)}: read at full resolution, its colour sites "
                     "evened out (docs/io.md)\n")


def print_json(data: dict[str, Any]) -> None:
    """Standard JSON (no NaN: callers put None for undefined values) on standard output."""
    json.dump(data, sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")


def solution_table(solution: AttitudeSolution, detections: Detections | None = None) -> str:
    """A short human-readable table of a solve (the format is in :data:`SOLUTION_FORMATS`)."""
    n_det = f" of {len(detections)} detected" if detections is not None else ""
    if not solution.solved:
        lines = [("status", solution.status.value), ("reason", solution.reason)]
        if detections is not None:
            lines.append(("stars", f"{len(detections)} detected"))
        lines.append(("time", f"{solution.solve_time_s * 1e3:.1f} ms"))
        return _table(lines)
    rms = float(np.sqrt(np.mean(solution.residuals_arcsec**2)))
    camera = require(solution.camera, "a solved frame's camera")
    return _table([
        ("status", "solved"),
        ("RA, Dec", f"{solution.ra_deg:.5f} deg, {solution.dec_deg:+.5f} deg (boresight, ICRS), "
                    f"in {constellation_of(solution.ra_deg, solution.dec_deg)}"),
        ("roll", f"{solution.roll_deg:.4f} deg"),
        ("FOV", f"{solution.fov_deg:.4f} deg horizontal (focal length {camera.fx:.1f} px, "
                f"{camera.pixel_scale_arcsec:.2f} arcsec/px)"
                + (f"; {FOV_SOURCE_WORDS[solution.fov_source]}" if solution.fov_source in FOV_SOURCE_WORDS else "")),
        *([("parity", "mirrored: the image is a mirror image of the sky")] if camera.mirrored else []),
        ("stars", f"{len(solution.matches)} matched{n_det}" + _guided_note(solution)),
        ("residual", f"{rms:.2f} arcsec rms"),
        ("1-sigma", f"{solution.sigma_cross_boresight_arcsec:.2f} arcsec cross-boresight, "
                    f"{solution.sigma_roll_arcsec:.2f} arcsec roll"),
        ("false match", f"{solution.false_match_prob:.1e} (upper bound)"),
        *([("epoch", f"J{solution.epoch_jyear:.2f} ({solution.epoch_source})")] if solution.epoch_source else []),
        ("time", f"{solution.solve_time_s * 1e3:.1f} ms"),
        ("qx qy qz qw", " ".join(f"{v:+.9f}" for v in require(solution.quaternion_xyzw, "the quaternion"))),
    ])


def _guided_note(solution: AttitudeSolution) -> str:
    """What the stars row says of the stars measured where the solution predicts them."""
    if not solution.guided_stars:
        return ""
    return f" ({solution.guided_stars} of them measured where the solution predicts them)"


def _table(lines: list[tuple[str, str]]) -> str:
    return "\n".join(f"{k:<12}{v}" for k, v in lines)


def report(solution: AttitudeSolution, detections: Detections | None, as_json: bool, ground=None) -> int:
    """Print a solve as JSON or as a table; exit status 0 when solved, 1 otherwise.

    ``ground`` (a :class:`startrack.calibrate._ground_solve.GroundSolution`) adds the time, site,
    altitude and azimuth of a photo taken from the ground."""
    extra = {} if ground is None else {
        "time_utc": ground.time.utc.isot, "site": ground.site.name,
        "latitude_deg": ground.site.latitude_deg, "longitude_deg": ground.site.longitude_deg,
        "altitude_deg": _finite_or_none(ground.altitude_deg), "azimuth_deg": _finite_or_none(ground.azimuth_deg)}
    streak = streak_fields(solution)
    if as_json:
        print_json({**solution_to_dict(solution, detections), **extra})
    else:
        print(solution_table(solution, detections))
        if streak and solution.solved:
            print(_table(_streak_rows(streak)))
        if extra and solution.solved:
            print(_table([("time", f"{extra['time_utc']} UTC at {extra['site']}"),
                          ("alt, az", f"{ground.altitude_deg:.4f} deg, {ground.azimuth_deg:.4f} deg "
                                      "(apparent altitude, azimuth east of north)")]))
    return 0 if solution.solved else 1


def _streak_rows(streak: dict) -> list[tuple[str, str]]:
    """Table rows of :func:`streak_fields`."""
    when = f"{streak['t_mid_s']:.4f} s after the exposure starts (mid-exposure)" if streak["t_mid_s"] is not None \
        else "mid-exposure"
    if streak["time_mid_utc"]:
        when += f", {streak['time_mid_utc']} UTC"
    if streak["rate_deg_s"] is not None:
        rate = "(" + ", ".join(f"{v:+.4f}" for v in streak["rate_deg_s"]) + ") deg/s, camera frame" \
            + ("" if streak["time_order_known"] else " (or its opposite: one frame cannot order the exposure in time)")
    else:
        rate = "(" + ", ".join(f"{v:+.4f}" for v in streak["turn_deg"]) + ") deg per exposure (no exposure time)"
    status = streak["rate_status"] + (f": {streak['rate_reason']}" if streak["rate_reason"] else "")
    return [("mode", "streaks (the stars smeared: solved from their streaks)"), ("attitude at", when),
            ("rate", rate), ("rate status", status)]


def _finite_or_none(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def non_empty(text: str) -> str:
    """argparse type: a name or a path that is not empty (an empty one was taken as not given)."""
    if not text.strip():
        raise argparse.ArgumentTypeError(f"expected a name, got {text!r}")
    return text


def positive_count(text: str) -> int:
    """argparse type: a whole number >= 1 (underscores allowed: 400_000_000; and a whole number in
    floating-point notation, 1e9, as the STARTRACK_MAX_PIXELS variable takes it)."""
    digits = text.replace("_", "")
    try:
        value = int(digits)
    except ValueError:
        try:
            number = float(digits)
        except ValueError:
            number = math.nan
        if not (math.isfinite(number) and number.is_integer()):
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        value = int(number)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text}")
    return value


MAX_UTC_OFFSET_HOURS = 14.0
"""The largest offset of a clock from UTC, hours (the civil zones run from -12 to +14; the web
tool's ``utc_offset_hours`` takes the same range)."""


def utc_offset_hours(text: str) -> float:
    """argparse type: an offset from UTC in hours, -14 to 14 (--utc-offset-hours)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected hours from UTC such as -6 or 5.5, got {text!r}") from None
    if not abs(value) <= MAX_UTC_OFFSET_HOURS:
        raise argparse.ArgumentTypeError(f"expected hours from UTC from -{MAX_UTC_OFFSET_HOURS:g} to "
                                         f"{MAX_UTC_OFFSET_HOURS:g}, got {text}")
    return value


def positive_int(text: str) -> int:
    """argparse type: a whole number >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number of pixels, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive whole number of pixels, got {text}")
    return value
