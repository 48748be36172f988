"""``startrack solve IMAGE``: lost-in-space attitude of an image."""

from __future__ import annotations

import argparse

from ..solve import solve_image
from .common import add_fov_options, fov_kwargs, report


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="startrack solve", description=__doc__)
    parser.add_argument("image", help="FITS, PNG, JPEG or TIFF file")
    add_fov_options(parser)
    parser.add_argument("--channel", help="colour channel to use: r, g or b (default: mean of R, G, B)")
    parser.add_argument("--epoch", type=float, help="catalog epoch as a Julian year (default 2000.0)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args(argv)
    solution, detections = solve_image(args.image, channel=args.channel, epoch=args.epoch, **fov_kwargs(args))
    return report(solution, detections, args.json)
