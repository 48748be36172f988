"""``startrack simulate``: render a star image of the Hipparcos sky with its truth.

Writes a FITS file (truth as header cards and a TRUTH table) or a 16-bit PNG / TIFF with a
``.truth.json`` file beside it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..io.truth_files import truth_to_dict, write_frame
from ..simulate import simulate_frame
from .common import print_json
from .scene_options import add_scene_options, scene_attitude, scene_camera, scene_seed, scene_sensor


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="startrack simulate", description=__doc__)
    add_scene_options(parser)
    parser.add_argument("--out", default="startrack-sim.fits", help="output .fits, .png or .tif path")
    parser.add_argument("--json", action="store_true", help="print the truth as JSON")
    args = parser.parse_args(argv)
    seed = scene_seed(args)
    rng = np.random.default_rng(seed)
    camera, sensor = scene_camera(args), scene_sensor(args)
    rot = scene_attitude(args, rng)
    sim = simulate_frame(camera, rot, max_mag=args.max_mag, sensor=sensor, rng=rng, noise=not args.no_noise)
    written = write_frame(Path(args.out), sim.image, sim.truth)
    truth = truth_to_dict(sim.truth)
    if args.json:
        print_json({"seed": seed, "files": [str(p) for p in written], **truth})
    else:
        print(f"wrote {', '.join(str(p) for p in written)}")
        print(f"seed {seed}; boresight RA {truth['ra_deg']:.5f} deg, Dec {truth['dec_deg']:+.5f} deg, "
              f"roll {truth['roll_deg']:.4f} deg; {len(truth['stars'])} stars in the image")
    return 0
