"""startrack simulate: render a star image of the Hipparcos sky with its truth.

Writes a FITS file (truth as header cards TRUE_RA, TRUE_DEC, TRUEROLL, TRUE_QX..TRUE_QW,
CATEPOCH, EXPTIME, FOCALPX, CAMERA and a TRUTH table of the stars) or a 16-bit PNG / TIFF with
a <stem>.truth.json file beside it. The folder of --out must exist; files are written
atomically, so an error leaves nothing behind.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..io.truth_files import check_frame_path, truth_to_dict, write_frame
from .common import print_json
from .scene_options import add_scene_options, simulate_scene

OUTPUT_FORMATS = """\
output (text, the default)
  wrote FILES
  seed N; boresight RA .. deg, Dec .. deg, roll .. deg; K stars in the image

output (--json)
  One object: seed, files (the paths written), ra_deg, dec_deg, roll_deg (boresight, ICRS, and
  the startrack.frames roll), qx, qy, qz, qw (rot_cam_from_icrs, scalar last), epoch_jyear,
  exposure_s, camera {width, height, fx, fy, cx, cy, k1, k2, k3, p1, p2, fov_deg, name} and
  stars: a list of {hip, x, y, mag, electrons} for the stars centred in the image (x, y in
  0-based pixels, brightest first). The .truth.json sidecar holds the same without seed, files.

exit status
  0 written; 2 misuse (bad option or output path), with one line
  'startrack simulate: error: ...' on standard error.
"""


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="startrack simulate", description=__doc__, epilog=OUTPUT_FORMATS,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_options(parser)
    parser.add_argument("--out", default="startrack-sim.fits",
                        help="output .fits, .png or .tif path (default startrack-sim.fits)")
    parser.add_argument("--json", action="store_true", help="print the truth as JSON")
    args = parser.parse_args(argv)
    out = Path(args.out)
    check_frame_path(out)
    seed, sim = simulate_scene(args)
    written = write_frame(out, sim.image, sim.truth)
    truth = truth_to_dict(sim.truth)
    if args.json:
        print_json({"seed": seed, "files": [str(p) for p in written], **truth})
    else:
        print(f"wrote {', '.join(str(p) for p in written)}")
        print(f"seed {seed}; boresight RA {truth['ra_deg']:.5f} deg, Dec {truth['dec_deg']:+.5f} deg, "
              f"roll {truth['roll_deg']:.4f} deg; {len(truth['stars'])} stars in the image")
    return 0
