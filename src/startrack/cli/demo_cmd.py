"""``startrack demo``: simulate a star image at a random attitude, solve it lost-in-space with no
field of view given, and compare the attitude with the truth. Writes the image, its truth and an
annotated PNG to the output folder."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..analysis.plots import plot_solution
from ..frames import attitude_error, boresight
from ..io.solution_json import solution_to_dict
from ..io.truth_files import write_frame
from ..simulate import simulate_frame
from ..solve import solve_image
from ..units import ARCSEC
from .common import print_json, solution_table
from .progress import ensure_database
from .scene_options import add_scene_options, scene_attitude, scene_camera, scene_seed, scene_sensor


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="startrack demo", description=__doc__)
    add_scene_options(parser)
    parser.add_argument("--out", default="startrack-demo", help="output folder (default startrack-demo)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    args = parser.parse_args(argv)
    seed = scene_seed(args)
    rng = np.random.default_rng(seed)
    camera, sensor = scene_camera(args), scene_sensor(args)
    rot = scene_attitude(args, rng)
    sim = simulate_frame(camera, rot, max_mag=args.max_mag, sensor=sensor, rng=rng, noise=not args.no_noise)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    written = write_frame(out / "demo.png", sim.image, sim.truth)
    ensure_database()
    solution, detections = solve_image(sim.image)
    plot_solution(sim.image, detections, solution, out / "demo_solved.png",
                  truth_xy=(sim.truth.x[sim.truth.inside()], sim.truth.y[sim.truth.inside()]))
    return _report(args, seed, camera, sim, solution, detections, [*written, out / "demo_solved.png"])


def _report(args, seed, camera, sim, solution, detections, files) -> int:
    errors = {}
    if solution.solved:
        total = float(attitude_error(sim.truth.rot_cam_from_icrs, solution.rot_cam_from_icrs)) / ARCSEC
        cross = np.arccos(np.clip(np.dot(boresight(sim.truth.rot_cam_from_icrs),
                                         boresight(solution.rot_cam_from_icrs)), -1, 1)) / ARCSEC
        errors = {"attitude_error_arcsec": total, "boresight_error_arcsec": float(cross),
                  "pixel_scale_arcsec": camera.pixel_scale_arcsec}
    if args.json:
        print_json({"seed": seed, **solution_to_dict(solution, detections), **errors,
                    "files": [str(f) for f in files]})
    else:
        print(f"simulated {camera.width} x {camera.height} px, FOV {camera.fov_deg:.2f} deg, seed {seed}: "
              f"{int(sim.truth.inside().sum())} stars; solving with no FOV given (searching 5-35 deg)\n")
        print(solution_table(solution, detections))
        if errors:
            print(f"{'error':<12}{errors['attitude_error_arcsec']:.2f} arcsec total "
                  f"({errors['attitude_error_arcsec'] / camera.pixel_scale_arcsec:.3f} px), "
                  f"boresight {errors['boresight_error_arcsec']:.2f} arcsec, against the truth")
        print(f"\nwrote {', '.join(str(f) for f in files)}")
    return 0 if solution.solved else 1
