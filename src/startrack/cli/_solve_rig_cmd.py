"""startrack solve-rig RIG.json HEAD=FILE [HEAD=FILE ...]: one attitude from several camera heads.

RIG.json describes the heads (startrack.CameraRig: each head's camera profile and mounting
rot_cam_from_body; see docs/rig.md). Each HEAD=FILE gives one head's stars: a CSV star list
(columns x, y [, flux | mag], 0-based pixel centres, as solve-stars reads) or an image (FITS,
PNG, JPEG, TIFF), whose stars are detected. For a split field of view, give the image of the
shared detector as DETECTOR=IMAGE: its spots are told apart by their PSF shape. Heads without a
file have no stars. The rig is identified lost-in-space on the head that can be (most stars
first), the other heads through their mountings, or jointly when no head can be alone.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import InvalidInputError
from ..io import read_star_list
from ..multihead import (
    HeadStars,
    RigOptions,
    check_method,
    detector_stars,
    rig_solution_table,
    rig_solution_to_dict,
    solve_head_stars,
)
from ..rig import CameraRig
from ..solve import epoch_jyear
from ._common import (
    add_epoch_option,
    add_max_pixels_option,
    add_method_option,
    apply_max_pixels_option,
    epoch_option,
    exit_status_epilog,
    print_json,
)
from ._parser import CommandParser
from ._progress import ensure_database_for

OUTPUT_FORMATS = """\
output (table, the default)
  status, RA / Dec / roll of the body +z axis, how the rig was identified, stars matched, the
  joint 1-sigma about the body axes, the consistency angle, the quaternion, time; then one line
  per head: stars matched, its own solution's status, the joint 1-sigma across and about its
  boresight.

output (--json)
  One object. Always: status ("ok", "too_few_stars", "no_match", "timeout"), reason,
  solve_time_s, heads. When solved also: qx, qy, qz, qw (rot_body_from_icrs, scalar last),
  ra_deg, dec_deg, roll_deg (body +z axis, startrack.frames roll), sigma_body_arcsec (1-sigma
  about body x, y, z), consistency_deg (largest angle between a head's own solution, through its
  mounting, and the joint one), mode ("single-head" or "joint-pattern"), seed_head, heads_used,
  inconsistent_heads, n_matched, false_match_prob. heads: per head name {status (its own
  solution), reason, n_stars, n_matched, used, inconsistent, centroid_sigma_px,
  sigma_cross_arcsec, sigma_roll_arcsec (joint, about its boresight), and when it has its own
  solution ra_deg, dec_deg, roll_deg, qx, qy, qz, qw (its rot_cam_from_icrs),
  own_sigma_cross_arcsec, own_sigma_roll_arcsec; matches: [{index, hip, residual_arcsec}]}.
  Undefined values are null.

""" + exit_status_epilog("0 solved; 1 not solved (the reason is printed); 2 misuse (bad option, unreadable rig or "
                         "file, a HEAD that is not in the rig), with one line 'startrack solve-rig: error: ...' on "
                         "standard error;")


def _parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack solve-rig", description=__doc__, epilog=OUTPUT_FORMATS,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("rig", metavar="RIG.json", help="the rig: heads, camera profiles, mountings")
    parser.add_argument("inputs", nargs="+", metavar="HEAD=FILE",
                        help="a head's star list (.csv) or image, or a split detector's image")
    add_method_option(parser)
    add_epoch_option(parser)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_max_pixels_option(parser)
    return parser


def _pairs(inputs: list[str], rig: CameraRig) -> dict[str, Path]:
    """HEAD=FILE arguments, checked against the rig's heads and detectors."""
    out: dict[str, Path] = {}
    for text in inputs:
        name, sep, file = text.partition("=")
        if not sep or not name or not file:
            raise InvalidInputError(f"expected HEAD=FILE, got {text!r}")
        if name not in rig and name not in rig.detectors:
            raise InvalidInputError(f"{name!r} is not a head of the rig (heads: {', '.join(rig.names)}; "
                                    f"detectors: {', '.join(rig.detectors)})")
        if name in out:
            raise InvalidInputError(f"{name!r} is given twice")
        out[name] = Path(file)
    return out


def _head_stars(name: str, path: Path, rig: CameraRig) -> dict[str, HeadStars]:
    """The star lists one HEAD=FILE argument gives."""
    if path.suffix.lower() == ".csv":
        if name not in rig:
            raise InvalidInputError(f"{name}={path}: a split detector's spots need its image to be told apart")
        stars = read_star_list(path)
        flux = stars.get("flux")
        if flux is None and "mag" in stars:
            flux = -stars["mag"]
        try:
            return {name: HeadStars.of(rig.head(name), stars["x"], stars["y"], flux)}
        except InvalidInputError as exc:
            raise InvalidInputError(f"{path}: {exc}") from None
    detector = rig.head(name).detector_name if name in rig else name
    if name in rig and len(rig.detectors[detector]) > 1:
        raise InvalidInputError(f"{name}={path}: head {name!r} shares detector {detector!r}; give {detector}=IMAGE")
    return detector_stars(path, rig, detector)[0]


def main(argv: list[str]) -> int:
    args = _parser().parse_args(argv)
    apply_max_pixels_option(args)
    check_method(args.method)
    epoch = epoch_option(args)
    rig = CameraRig.load(args.rig)
    stars = {h.name: HeadStars.of(h, [], []) for h in rig}
    for name, path in _pairs(args.inputs, rig).items():
        stars.update(_head_stars(name, path, rig))
    for head in rig:
        ensure_database_for(None, None, head.camera)
    solution = solve_head_stars(stars, rig, epoch_jyear(epoch), args.method, RigOptions())
    data = rig_solution_to_dict(solution, rig, {n: len(s) for n, s in stars.items()})
    if args.json:
        print_json(data)
    else:
        print(rig_solution_table(data))
    return 0 if solution.solved else 1
