"""Pieces every subcommand shares: FOV options, output, and turning errors into one line."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

import numpy as np

from ..camera import Camera, get_preset
from ..errors import InvalidInputError
from ..io.solution_json import solution_to_dict
from ..results import AttitudeSolution, Detections


def add_fov_options(parser: argparse.ArgumentParser) -> None:
    """--fov-deg, --fov-range-deg, --camera (mutually exclusive)."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--fov-deg", type=float, metavar="F", help="horizontal field of view, trusted to +-3 %%")
    group.add_argument("--fov-range-deg", type=float, nargs=2, metavar=("LO", "HI"),
                       help="range of horizontal fields of view to search (default 5 35)")
    group.add_argument("--camera", metavar="PRESET", help="a calibrated camera preset (fixes the focal length)")


def fov_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments for the solvers from the parsed FOV options."""
    camera: Camera | None = get_preset(args.camera) if args.camera else None
    fov_range = tuple(args.fov_range_deg) if args.fov_range_deg else None
    return {"fov_deg": args.fov_deg, "fov_range_deg": fov_range, "camera": camera}


def print_json(data: dict[str, Any]) -> None:
    json.dump(data, sys.stdout, indent=2)
    sys.stdout.write("\n")


def solution_table(solution: AttitudeSolution, detections: Detections | None = None) -> str:
    """A short human-readable table of a solve."""
    if not solution.solved:
        return f"status      {solution.status.value}\nreason      {solution.reason}\n" \
               f"time        {solution.solve_time_s * 1e3:.1f} ms"
    q = solution.quaternion_xyzw
    rms = float(np.sqrt(np.mean(solution.residuals_arcsec**2)))
    n_det = f" of {len(detections)} detected" if detections is not None else ""
    lines = [
        ("status", "solved"),
        ("RA, Dec", f"{solution.ra_deg:.5f} deg, {solution.dec_deg:+.5f} deg (boresight, ICRS)"),
        ("roll", f"{solution.roll_deg:.4f} deg"),
        ("FOV", f"{solution.fov_deg:.4f} deg horizontal (focal length {solution.camera.fx:.1f} px)"),
        ("stars", f"{len(solution.matches)} matched{n_det}"),
        ("residual", f"{rms:.2f} arcsec rms"),
        ("1-sigma", f"{solution.sigma_cross_boresight_arcsec:.2f} arcsec cross-boresight, "
                    f"{solution.sigma_roll_arcsec:.2f} arcsec roll"),
        ("false match", f"{solution.false_match_prob:.1e} (upper bound)"),
        ("time", f"{solution.solve_time_s * 1e3:.1f} ms"),
        ("qx qy qz qw", " ".join(f"{v:+.9f}" for v in q)),
    ]
    return "\n".join(f"{k:<12}{v}" for k, v in lines)


def report(solution: AttitudeSolution, detections: Detections | None, as_json: bool) -> int:
    """Print a solve as JSON or as a table; exit status 0 when solved, 1 otherwise."""
    if as_json:
        print_json(solution_to_dict(solution, detections))
    else:
        print(solution_table(solution, detections))
    return 0 if solution.solved else 1


def positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise InvalidInputError(f"expected a positive whole number, got {text}")
    return value
