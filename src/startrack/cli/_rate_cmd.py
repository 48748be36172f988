"""``startrack rate``: angular rate from one streaked image, or from a pair of images.

One image (Sease 2013 ch. 4, no catalog): the streaks' two ends are located, grouped into the
start and end of the exposure, and the rate is solved between the groups (OLAE) with the RSO
indicators; ``--exposure-s`` is the time between the ends. Two images (Samaan 2002 step 6 /
Huffman 2006 §7.2): the stars found in both are matched frame to frame (the pairs that agree on
one rotation) and the relative attitude over ``--dt-s`` gives the rate, reported only when at
least four stars match and fit the rotation within the centroid noise. Either way no star catalog
is used. A calibrated camera is needed (``--camera`` preset or ``--fov-deg``, pinhole at the
image centre).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace

import numpy as np

from ..camera import Camera, get_preset
from ..errors import InvalidInputError
from ..io import read_image
from ..rate import (
    METHODS,
    SEGMENT,
    RateEstimate,
    StreakRate,
    find_streaks,
    rate_from_frames,
    streak_rate,
)
from ..units import DEG
from ._common import (
    add_max_pixels_option,
    apply_max_pixels_option,
    check_finite_options,
    check_time_option,
    exit_status_epilog,
    print_json,
)
from ._parser import CommandParser

EPILOG = """\
output: status, reason, rate (deg/s), axis (camera frame, unit), omega_deg_s (x, y, z),
sigma_deg_s (1-sigma of each component, when known), and for one image the streaks used and the
RSO candidates (streak index, ends in 0-based pixels); for a pair the stars matched, the stars
found in each image and the rms misfit of the matched stars to the rotation (px). --json gives
the same as an object.

""" + exit_status_epilog("0 rate found; 1 not found (the status and reason are printed); 2 misuse, with one line "
                         "'startrack rate: error: ...' on standard error;")

MAX_BIAS_PX = 10.0
"""Largest |--bias-px|: a corner detector pulls the ends in by about a PSF width (0.6-2.3 px)."""
MAX_MOTION_DEG = 90.0
"""Largest --max-motion-deg."""
CENTROID_SIGMA_PX = 0.5
"""1-sigma centroid error of a star (px per axis) assumed when matching an image pair."""


def build_parser() -> argparse.ArgumentParser:
    parser = CommandParser(prog="startrack rate", description=__doc__.splitlines()[0], epilog=EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("images", nargs="+", metavar="IMAGE", help="one streaked image, or two images")
    camera = parser.add_mutually_exclusive_group(required=True)
    camera.add_argument("--camera", metavar="PRESET", help="a calibrated camera preset")
    camera.add_argument("--fov-deg", type=float, metavar="F", help="horizontal FOV of a pinhole camera, deg")
    parser.add_argument("--exposure-s", type=float, help="exposure of a streaked image, s (one image)")
    parser.add_argument("--dt-s", type=float, help="time between the two images, s (two images)")
    parser.add_argument("--detector", choices=METHODS, default=SEGMENT,
                        help="streak endpoint method: the segment fit, or a corner detector")
    parser.add_argument("--bias-px", type=float, default=0.0, help="calibrated inward endpoint bias, px")
    parser.add_argument("--prior-rate-deg-s", type=float, nargs=3, metavar=("WX", "WY", "WZ"),
                        help="a rough rate (camera frame) to order the streak ends in time")
    parser.add_argument("--max-motion-deg", type=float, default=1.0,
                        help="largest star motion between two images, deg (pair matching gate, default 1)")
    parser.add_argument("--json", action="store_true", help="print a JSON object")
    add_max_pixels_option(parser)
    return parser


def _camera(args, width: int, height: int) -> Camera:
    if args.camera:
        camera = get_preset(args.camera)
        if (camera.width, camera.height) != (width, height):
            size = f"{camera.width} x {camera.height}"
            raise InvalidInputError(f"camera {args.camera} is {size} px, the image {width} x {height}")
        return camera
    return Camera.from_fov(width, height, fov_deg=args.fov_deg)


def _rate_fields(rate: RateEstimate) -> dict:
    sigma = rate.sigma_rad_s / DEG
    return {"status": rate.status.value, "reason": rate.reason, "rate_deg_s": rate.rate_deg_s if rate.ok else None,
            "axis": rate.axis.tolist() if rate.ok else None,
            "omega_deg_s": (rate.omega_rad_s / DEG).tolist() if rate.ok else None,
            "sigma_deg_s": sigma.tolist() if rate.ok and np.all(np.isfinite(sigma)) else None, "method": rate.method}


def _check_options(args) -> None:
    """Refuse NaN / infinite numbers and values out of their sensible ranges (stated in the message)."""
    check_finite_options(args)
    if not abs(args.bias_px) <= MAX_BIAS_PX:
        raise InvalidInputError(f"--bias-px must be between -{MAX_BIAS_PX:g} and {MAX_BIAS_PX:g} px, "
                                f"got {args.bias_px:g}")
    if not 0 < args.max_motion_deg <= MAX_MOTION_DEG:
        raise InvalidInputError(f"--max-motion-deg must be above 0 and at most {MAX_MOTION_DEG:g} deg, "
                                f"got {args.max_motion_deg:g}")
    if args.prior_rate_deg_s is not None and not np.any(args.prior_rate_deg_s):
        raise InvalidInputError("--prior-rate-deg-s must be a non-zero rate (it orders the streak ends in time)")


def _one_image(args, image) -> tuple[dict, RateEstimate]:
    check_time_option(args.exposure_s, "--exposure-s", "one image")
    camera = _camera(args, image.shape[1], image.shape[0])
    prior = None if args.prior_rate_deg_s is None else np.array(args.prior_rate_deg_s) * DEG
    result: StreakRate = streak_rate(image, camera, args.exposure_s, detector=args.detector, bias_px=args.bias_px,
                                     prior_omega_rad_s=prior)
    out = _rate_fields(result.rate) | {"streaks": len(result.measurement.regions),
                                       "time_order_known": result.time_order_known, "rso_candidates": []}
    if result.rso is not None:
        m = result.measurement
        out["rso_candidates"] = [{"index": int(i), "start_xy": m.ends_a[i].tolist(), "end_xy": m.ends_b[i].tolist()}
                                 for i in result.rso.candidates]
    return out, result.rate


def _centroids(image) -> np.ndarray:
    return np.array([r.centroid_xy for r in find_streaks(image, min_area_px=4).regions]).reshape(-1, 2)


def _two_images(args, first, second) -> tuple[dict, RateEstimate]:
    check_time_option(args.dt_s, "--dt-s", "two images", signed=True)
    if first.shape != second.shape:
        raise InvalidInputError(f"the two images differ in size: {first.shape} and {second.shape}")
    camera = _camera(args, first.shape[1], first.shape[0])
    a, b = _centroids(first), _centroids(second)  # brightest first
    va, vb = camera.pixel_to_vector(a[:, 0], a[:, 1]), camera.pixel_to_vector(b[:, 0], b[:, 1])
    found = rate_from_frames(va, vb, args.dt_s, max_angle_rad=args.max_motion_deg * DEG,
                             sigma_rad=CENTROID_SIGMA_PX / camera.fx)
    rate = replace(found.estimate, reason=found.estimate.reason.replace("max_angle_rad", "--max-motion-deg"))
    misfit = found.residual_rms_rad * camera.fx
    return _rate_fields(rate) | {"stars_matched": int(len(found.pairs)), "stars": [len(a), len(b)],
                                 "residual_rms_px": float(misfit) if np.isfinite(misfit) else None}, rate


def _print_table(out: dict) -> None:
    for key, value in out.items():
        if isinstance(value, float):
            value = f"{value:.6g}"
        elif isinstance(value, list) and value and isinstance(value[0], float):
            value = " ".join(f"{v:+.6f}" for v in value)
        print(f"{key:<17} {value}")


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    apply_max_pixels_option(args)
    _check_options(args)
    if len(args.images) > 2:
        raise InvalidInputError(f"give one streaked image or two images, got {len(args.images)}")
    images = [np.asarray(read_image(path).data, dtype=float) for path in args.images]
    out, rate = _one_image(args, images[0]) if len(images) == 1 else _two_images(args, *images)
    print_json(out) if args.json else _print_table(out)
    return 0 if rate.ok else 1


if __name__ == "__main__":
    sys.exit(main())
