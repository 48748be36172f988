"""startrack availability: how many catalog stars a camera sees over random pointings (Jacobs 1995
Fig. 5-1 / Table 5-1; Huffman 2006 Table 5.1), with a histogram plot; and the size of a uniform
reduced onboard catalog (Huffman 2006 §5.5.4: the N brightest stars at every pointing).

With --rig RIG.json (a startrack.CameraRig): the fraction of random body attitudes where at least
one head, and the joint solution, has enough stars (docs/rig.md), each head excluded when the Sun,
the Earth's limb or the Moon enters its exclusion cone (angles per head in the rig file; the bodies
seen from a dawn-dusk orbit at --altitude-km at --time; --no-exclusion leaves them out)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ..camera import Camera, get_preset
from ..catalog import load_catalog, thin_uniform
from ..errors import InvalidInputError
from ..io import open_output, output_target
from ._common import check_finite_options, exit_status_epilog, positive_count, print_json, time_option
from ._parser import CommandParser
from ._progress import ProgressBar


def _camera(args) -> Camera:
    if args.camera is not None:
        if args.fov_deg is not None:
            raise InvalidInputError("--camera has its field of view; give --camera PRESET or --fov-deg F, not both")
        return get_preset(args.camera)
    if args.fov_deg is None:
        raise InvalidInputError("give --camera PRESET or --fov-deg F (with --width and --height)")
    return Camera.from_fov(args.width, args.height, args.fov_deg)


EPILOG = (
    "--json keys: camera, fov_deg, fov_height_deg, max_mag, catalog_stars, pointings, mean, min, max, "
    "p_below_3, p_below_4, probability (pointing fraction by star count), reduced_catalog_stars.\n"
    "With --rig: rig, max_mag, pointings, time_utc (null without exclusion), altitude_km, min_stars, "
    "min_joint_stars, any_head, joint (fractions of pointings), heads: {name: {enough, blinded, "
    "mean_stars}}.\n\n" + exit_status_epilog(
        "0 done; 2 misuse (bad option or input), with one line 'startrack availability: error: ...' on standard "
        "error;"))

MAX_POINTINGS = 10_000_000
"""Most random pointings (the counts of 10^7 pointings take about a minute and some 100 MB)."""


def _check(args) -> None:
    """Refuse option values that no run can use, before any work (NaN, inf, a bad time, ...)."""
    check_finite_options(args)
    time_option(args)
    if args.plot is not None and Path(args.plot).suffix.lower() != ".png" and args.plot != "-":
        raise InvalidInputError(f"--plot writes a PNG: give a .png file name, got {args.plot}")
    if args.plot is not None:
        output_target(args.plot)
    if args.pointings > MAX_POINTINGS:
        raise InvalidInputError(f"--pointings must be at most {MAX_POINTINGS:,}, got {args.pointings:,}")
    if not -2.0 <= args.max_mag <= 20.0:
        raise InvalidInputError(f"--max-mag must be a V magnitude from -2 to 20, got {args.max_mag:g}")
    if not 0.0 < args.altitude_km <= 1e6:
        raise InvalidInputError(f"--altitude-km must be above 0 and at most 1e6 km, got {args.altitude_km:g}")
    for name in ("min_stars", "min_joint_stars", "reduced_per_fov", "seed"):
        value = getattr(args, name)
        if value is not None and value < (0 if name == "seed" else 1):
            raise InvalidInputError(f"--{name.replace('_', '-')} must be a whole number >= "
                                    f"{0 if name == 'seed' else 1}, got {value}")


def main(argv: list[str]) -> int:
    parser = CommandParser(prog="startrack availability", description=__doc__, epilog=EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--camera", help="camera preset")
    parser.add_argument("--fov-deg", type=float, help="pinhole camera: horizontal FOV")
    parser.add_argument("--width", type=positive_count, default=1024)
    parser.add_argument("--height", type=positive_count, default=1024)
    parser.add_argument("--max-mag", type=float, default=6.0, help="catalog limit, V (default 6.0)")
    parser.add_argument("--pointings", type=positive_count, default=100_000,
                        help=f"random pointings (Jacobs 1995 used 10^6; at most {MAX_POINTINGS:,})")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--plot", help="write the histogram to this PNG")
    parser.add_argument("--reduced-per-fov", type=int, metavar="N",
                        help="also build the uniform reduced catalog: N brightest stars per field")
    parser.add_argument("--json", action="store_true")
    rig = parser.add_argument_group("camera rig")
    rig.add_argument("--rig", metavar="RIG.json", help="availability of this rig of camera heads")
    rig.add_argument("--min-stars", type=int, default=4, help="stars a head needs alone (default 4)")
    rig.add_argument("--min-joint-stars", type=int, default=6, help="stars the joint pattern needs (default 6)")
    rig.add_argument("--time", default="2025-03-20T12:00:00", metavar="UTC",
                     help="time of the Sun / Moon positions (ISO, default 2025-03-20T12:00:00)")
    rig.add_argument("--altitude-km", type=float, default=500.0, help="dawn-dusk orbit altitude (default 500)")
    rig.add_argument("--no-exclusion", action="store_true", help="ignore the Sun, the Earth and the Moon")
    args = parser.parse_args(argv)
    _check(args)
    if args.rig is not None:
        return _rig(args)
    from ..analysis import star_counts

    camera = _camera(args)
    result = star_counts(camera, args.max_mag, args.pointings, rng=args.seed, progress=ProgressBar("  pointings"))
    report = {"camera": camera.name or "pinhole", "fov_deg": camera.fov_deg, "fov_height_deg": camera.fov_height_deg,
              "max_mag": args.max_mag, "catalog_stars": result.n_catalog, "pointings": args.pointings,
              "mean": float(result.counts.mean()), "min": int(result.counts.min()), "max": int(result.counts.max()),
              "p_below_3": result.probability_below(3), "p_below_4": result.probability_below(4),
              "probability": {str(n): result.probability(n) for n in range(len(result.histogram))}}
    if args.reduced_per_fov:
        reduced = thin_uniform(load_catalog().brighter_than(args.max_mag), args.reduced_per_fov,
                               math.radians(camera.fov_diagonal_deg) / 2.0)
        report["reduced_catalog_stars"] = len(reduced)
    if args.plot:
        from ..analysis import plot_star_counts

        with open_output(args.plot, "wb") as fh:  # the rules of startrack.io._atomic; PNG as the help says
            plot_star_counts(result, fh)
    if args.json:
        print_json(report)
    else:
        _print_table(report)
    return 0


def _print_table(report: dict) -> None:
    print(f"{report['camera']}: {report['fov_deg']:.2f} x {report['fov_height_deg']:.2f} deg, "
          f"V <= {report['max_mag']:g} ({report['catalog_stars']} stars), {report['pointings']} random pointings")
    print(f"stars in the image: mean {report['mean']:.2f}, min {report['min']}, max {report['max']}")
    print(f"P(< 3 stars) = {report['p_below_3']:.5f}, P(< 4 stars) = {report['p_below_4']:.5f}")
    for n in range(6):
        print(f"  P({n}) = {report['probability'].get(str(n), 0.0) * 1e3:.3f} x 1e-3")
    if "reduced_catalog_stars" in report:
        print(f"uniform reduced catalog: {report['reduced_catalog_stars']} stars")


def _rig(args) -> int:
    """--rig: the rig's availability (module docstring)."""
    from ..multihead import dawn_dusk_bodies, rig_availability
    from ..rig import CameraRig

    given = [o for o, v in (("--camera", args.camera), ("--fov-deg", args.fov_deg), ("--plot", args.plot),
                            ("--reduced-per-fov", args.reduced_per_fov)) if v is not None]
    if given:
        raise InvalidInputError(f"--rig has its cameras; leave out {', '.join(given)}")
    rig = CameraRig.load(args.rig)
    bodies = None if args.no_exclusion else dawn_dusk_bodies(args.time, args.altitude_km)
    result = rig_availability(rig, args.max_mag, args.pointings, rng=args.seed, bodies=bodies,
                              min_stars=args.min_stars, min_joint_stars=args.min_joint_stars,
                              progress=ProgressBar("  pointings"))
    report = {"rig": str(args.rig), "max_mag": args.max_mag, "pointings": args.pointings,
              "time_utc": None if bodies is None else args.time, "altitude_km": args.altitude_km,
              "min_stars": args.min_stars, "min_joint_stars": args.min_joint_stars, **result.summary()}
    if args.json:
        print_json(report)
        return 0
    print(f"{args.rig}: {len(rig)} heads, V <= {args.max_mag:g}, {args.pointings} random body attitudes"
          + ("" if bodies is None else f", exclusion at {args.time} UTC from {args.altitude_km:g} km"))
    print(f"at least one head with {args.min_stars}+ stars: {report['any_head']:.4f}")
    print(f"joint solution (or a triangle and {args.min_joint_stars} stars in all): {report['joint']:.4f}")
    for name, head in report["heads"].items():
        print(f"  {name}: enough {head['enough']:.4f}, blinded {head['blinded']:.4f}, "
              f"mean {head['mean_stars']:.2f} stars")
    return 0
