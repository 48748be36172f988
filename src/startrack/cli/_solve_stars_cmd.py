"""startrack solve-stars FILE.csv --width W --height H: lost-in-space attitude of a star list.

The CSV has a header row with at least the columns x and y (0-based pixel centres,
x = column); an optional flux (larger is brighter) or mag column orders the stars, otherwise
they are taken brightest first as listed. Lines starting with # are comments. SExtractor's
catalogs (ASCII_HEAD or FITS_LDAC: X_IMAGE, Y_IMAGE) and astrometry.net's xylists (.xyls, .axy:
X, Y) are read as they are, their 1-based positions made 0-based. --width and --height give the
image size (not needed with --camera, whose size is used, or with an astrometry.net .axy, whose
IMAGEW and IMAGEH are). The catalog epoch is --epoch, else the year of --time, else
J2000.0; the solution says which (epoch_jyear, epoch_source).
"""

from __future__ import annotations

import argparse

from ..errors import InvalidInputError
from ..identify import PARITIES, check_pixel_aspect, parse_utc
from ..io import read_star_list, star_list_image_size
from ..solve import solve_stars
from ._batch_warmup import warm_up
from ._common import (
    SOLUTION_FORMATS,
    add_epoch_option,
    add_fov_options,
    add_max_pixels_option,
    add_method_option,
    add_timeout_option,
    apply_max_pixels_option,
    epoch_option,
    fov_kwargs,
    method_kwargs,
    positive_int,
    report,
)
from ._parser import CommandParser
from ._progress import ensure_database_for


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack solve-stars", description=__doc__, epilog=SOLUTION_FORMATS,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("starlist",
                        help="CSV with columns x, y [, flux | mag], a SExtractor catalog or an astrometry.net xylist")
    parser.add_argument("--width", type=positive_int, metavar="W", help="image width in pixels")
    parser.add_argument("--height", type=positive_int, metavar="H", help="image height in pixels")
    add_fov_options(parser)
    add_method_option(parser)
    add_timeout_option(parser)
    add_epoch_option(parser)
    add_aspect_option(parser)
    add_parity_option(parser, "normal")
    parser.add_argument("--time", metavar="UTC", help="when the stars were observed, ISO 8601 UTC: its year is the "
                                                      "catalog epoch unless --epoch is given")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_max_pixels_option(parser)
    return parser


def add_aspect_option(parser: argparse.ArgumentParser) -> None:
    """--pixel-aspect A, or LO HI to search (shared with ``startrack solve``)."""
    parser.add_argument("--pixel-aspect", type=float, nargs="+", metavar="A",
                        help="height of a pixel on the sky over its width (fx / fy; default: square, refined in the "
                             "fit), or LO HI to search that range (slower); not with --camera")


def add_parity_option(parser: argparse.ArgumentParser, default: str) -> None:
    """--parity normal | mirrored | either (shared with ``startrack solve``; ``default`` is what
    the help says None means)."""
    parser.add_argument("--parity", choices=PARITIES, default=None,
                        help=f"whether the image is a mirror image of the sky (a star diagonal, a flipped file): "
                             f"normal, mirrored, or either to search both (default: {default}, or the camera's)")


def aspect_option(args: argparse.Namespace) -> float | tuple[float, float] | None:
    """The checked --pixel-aspect: a number, a (lo, hi) range, or None."""
    if args.pixel_aspect is None:
        return None
    values = args.pixel_aspect
    check_pixel_aspect(values, "--pixel-aspect")
    return values[0] if len(values) == 1 else (values[0], values[1])


def time_option(args: argparse.Namespace):
    """The checked --time (astropy Time, UTC) or None."""
    return None if args.time is None else parse_utc(args.time, "--time")


def solver_epoch(args: argparse.Namespace):
    """The epoch the solve is asked for: --epoch (a Julian year), else --time, else None."""
    epoch, when = epoch_option(args), time_option(args)
    return epoch if epoch is not None else when


def main(argv: list[str]) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.camera is None and (args.width is None or args.height is None):
        size = star_list_image_size(args.starlist)
        if size is None:
            parser.error("--width and --height are required unless --camera or the star list's "
                         "FITS header (IMAGEW, IMAGEH) gives them")
        args.width, args.height = args.width or size[0], args.height or size[1]
    apply_max_pixels_option(args)
    solver_options = {**fov_kwargs(args), "epoch": solver_epoch(args), **method_kwargs(args),
                      "pixel_aspect": aspect_option(args), "parity": args.parity}
    _check_size(args, solver_options["camera"])
    stars = read_star_list(args.starlist)
    flux = stars.get("flux")
    if flux is None and "mag" in stars:
        flux = -stars["mag"]
    fov_options = {key: solver_options[key] for key in ("fov_deg", "fov_range_deg", "camera")}
    ensure_database_for(**fov_options, height_ratio=args.height / args.width if args.width and args.height else 1.0)
    warm_up(**fov_options)  # the compiled kernels loaded (or compiled, with a message) outside the solve time
    try:
        solution = solve_stars(stars["x"], stars["y"], width=args.width, height=args.height, flux=flux,
                               **solver_options)
    except InvalidInputError as exc:  # a problem with the list's content (NaN, out of the frame)
        raise InvalidInputError(f"{args.starlist}: {exc}") from exc
    return report(solution, None, args.json)


def _check_size(args: argparse.Namespace, camera) -> None:
    """The image size within --max-pixels; with --camera, --width / --height only if they agree."""
    from ..io import check_image_size

    if camera is None:
        check_image_size(args.width, args.height, None, "--width x --height")
        return
    for name, given, size in (("--width", args.width, camera.width), ("--height", args.height, camera.height)):
        if given is not None and given != size:
            raise InvalidInputError(f"{name} {given} disagrees with camera {args.camera!r} "
                                    f"({camera.width} x {camera.height} px); leave it out")
