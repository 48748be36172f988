"""``startrack solve-stars FILE.csv --width W --height H``: lost-in-space attitude of a star list.

The CSV has a header row with at least the columns ``x`` and ``y`` (0-based pixel centres,
x = column); an optional ``flux`` (larger is brighter) or ``mag`` column orders the stars,
otherwise they are taken brightest first as listed.
"""

from __future__ import annotations

import argparse

from ..io import read_star_list
from ..solve import solve_stars
from .common import add_fov_options, fov_kwargs, positive_int, report


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="startrack solve-stars", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("starlist", help="CSV file with columns x, y [, flux | mag]")
    parser.add_argument("--width", type=positive_int, required=False, help="image width in pixels")
    parser.add_argument("--height", type=positive_int, required=False, help="image height in pixels")
    add_fov_options(parser)
    parser.add_argument("--epoch", type=float, help="catalog epoch as a Julian year (default 2000.0)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args(argv)
    if args.camera is None and (args.width is None or args.height is None):
        parser.error("--width and --height are required unless --camera gives them")
    stars = read_star_list(args.starlist)
    flux = stars.get("flux")
    if flux is None and "mag" in stars:
        flux = -stars["mag"]
    solution = solve_stars(stars["x"], stars["y"], width=args.width, height=args.height, flux=flux,
                           epoch=args.epoch, **fov_kwargs(args))
    return report(solution, None, args.json)
