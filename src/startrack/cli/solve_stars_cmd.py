"""startrack solve-stars FILE.csv --width W --height H: lost-in-space attitude of a star list.

The CSV has a header row with at least the columns x and y (0-based pixel centres,
x = column; subtract 1 from FITS / astrometry.net positions); an optional flux (larger is
brighter) or mag column orders the stars, otherwise they are taken brightest first as listed.
Lines starting with # are comments. --width and --height give the image size (not needed with
--camera, whose size is used).
"""

from __future__ import annotations

import argparse

from ..errors import InvalidInputError
from ..io import read_star_list
from ..solve import solve_stars
from .common import (
    SOLUTION_FORMATS,
    add_epoch_option,
    add_fov_options,
    add_method_option,
    epoch_option,
    fov_kwargs,
    positive_int,
    report,
)
from .progress import ensure_database_for


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="startrack solve-stars", description=__doc__, epilog=SOLUTION_FORMATS,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("starlist", help="CSV file with columns x, y [, flux | mag]")
    parser.add_argument("--width", type=positive_int, metavar="W", help="image width in pixels")
    parser.add_argument("--height", type=positive_int, metavar="H", help="image height in pixels")
    add_fov_options(parser)
    add_method_option(parser)
    add_epoch_option(parser)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    return parser


def main(argv: list[str]) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.camera is None and (args.width is None or args.height is None):
        parser.error("--width and --height are required unless --camera gives them")
    solver_options = {**fov_kwargs(args), "epoch": epoch_option(args), "method": args.method}
    _check_size(args, solver_options["camera"])
    stars = read_star_list(args.starlist)
    flux = stars.get("flux")
    if flux is None and "mag" in stars:
        flux = -stars["mag"]
    ensure_database_for(solver_options["fov_deg"], solver_options["fov_range_deg"], solver_options["camera"])
    try:
        solution = solve_stars(stars["x"], stars["y"], width=args.width, height=args.height, flux=flux,
                               **solver_options)
    except InvalidInputError as exc:  # a problem with the list's content (NaN, out of the frame)
        raise InvalidInputError(f"{args.starlist}: {exc}") from exc
    return report(solution, None, args.json)


def _check_size(args: argparse.Namespace, camera) -> None:
    """With --camera, --width / --height may be given only if they agree with the preset."""
    if camera is None:
        return
    for name, given, size in (("--width", args.width, camera.width), ("--height", args.height, camera.height)):
        if given is not None and given != size:
            raise InvalidInputError(f"{name} {given} disagrees with camera {args.camera!r} "
                                    f"({camera.width} x {camera.height} px); leave it out")
