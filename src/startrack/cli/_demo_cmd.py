"""startrack demo: simulate a star image at a random attitude, solve it lost-in-space with no
field of view given (searching 3 to 100 deg), and compare the attitude with the truth. Writes
demo.png (16 bit), demo.truth.json and an annotated demo_solved.png to the output folder
(created if missing)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..analysis import plot_solution
from ..errors import require
from ..frames import angle_between, attitude_error, boresight
from ..io import solution_to_dict, write_frame
from ..solve import DEFAULT_FOV_RANGE_DEG, solve_image
from ..units import ARCSEC
from ._batch_warmup import warm_up
from ._common import (
    SOLUTION_FORMATS,
    add_max_pixels_option,
    apply_max_pixels_option,
    check_output_folder,
    exit_status_epilog,
    non_empty,
    print_json,
    solution_table,
)
from ._parser import CommandParser
from ._progress import ensure_database
from ._render_limits import check_render_options
from ._scene_options import add_scene_options, scene_epoch, simulate_scene

OUTPUT_FORMATS = SOLUTION_FORMATS.split("exit status")[0] + """\
demo adds
  a first line with the simulated scene, an 'error' line (attitude error against the truth:
  total angle and boresight angle, arcsec) and the files written; with --json the keys seed,
  attitude_error_arcsec, boresight_error_arcsec, pixel_scale_arcsec (when solved) and files.

""" + exit_status_epilog("0 solved; 1 not solved; 2 misuse, with one line 'startrack demo: error: ...' on standard "
                         "error;")


def main(argv: list[str]) -> int:
    parser = CommandParser(prog="startrack demo", description=__doc__, epilog=OUTPUT_FORMATS,
                           formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_options(parser)
    parser.add_argument("--out", default="startrack-demo", type=non_empty,
                        help="output folder (default startrack-demo)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    add_max_pixels_option(parser)
    args = parser.parse_args(argv)
    apply_max_pixels_option(args)  # the limit of the image rendered and of the one solved
    out = Path(args.out)
    check_output_folder(out)
    check_render_options(args)  # --width x --height within --max-pixels, before anything is rendered
    seed, sim = simulate_scene(args)
    out.mkdir(parents=True, exist_ok=True)
    written = write_frame(out / "demo.png", sim.image, sim.truth)
    ensure_database(DEFAULT_FOV_RANGE_DEG)
    epoch = scene_epoch(args)
    warm_up(epoch=epoch, image=sim.image)  # loading (or compiling) the kernels is not part of the solve time
    solution = solve_image(sim.image, epoch=epoch)
    detections = require(solution.detections, "the demo frame's detections")
    inside = sim.truth.inside()
    plot_solution(sim.image, detections, solution, out / "demo_solved.png",
                  truth_xy=(sim.truth.x[inside], sim.truth.y[inside]))
    return _report(args, seed, sim, solution, detections, [*written, out / "demo_solved.png"])


def _errors(sim, solution) -> dict[str, float]:
    """Attitude and boresight error against the truth, arcsec (empty when unsolved)."""
    if not solution.solved:
        return {}
    truth_rot = sim.truth.rot_cam_from_icrs
    total = float(attitude_error(truth_rot, solution.rot_cam_from_icrs)) / ARCSEC
    cross = float(angle_between(boresight(truth_rot), boresight(solution.rot_cam_from_icrs))) / ARCSEC
    return {"attitude_error_arcsec": total, "boresight_error_arcsec": cross,
            "pixel_scale_arcsec": sim.truth.camera.pixel_scale_arcsec}


def _report(args, seed, sim, solution, detections, files) -> int:
    errors = _errors(sim, solution)
    camera = sim.truth.camera
    if args.json:
        print_json({"seed": seed, **solution_to_dict(solution, detections), **errors,
                    "files": [str(f) for f in files]})
    else:
        lo, hi = DEFAULT_FOV_RANGE_DEG
        print(f"simulated {camera.width} x {camera.height} px, FOV {camera.fov_deg:.2f} deg, seed {seed}: "
              f"{int(sim.truth.inside().sum())} stars; solving with no FOV given (searching {lo:g}-{hi:g} deg)\n")
        print(solution_table(solution, detections))
        if errors:
            print(f"{'error':<12}{errors['attitude_error_arcsec']:.2f} arcsec total "
                  f"({errors['attitude_error_arcsec'] / errors['pixel_scale_arcsec']:.3f} px), "
                  f"boresight {errors['boresight_error_arcsec']:.2f} arcsec, against the truth")
        print(f"\nwrote {', '.join(str(f) for f in files)}")
    return 0 if solution.solved else 1
