"""Seed reproductions for streaked and smeared images, run as campaigns, ours beside the seeds'.

Each part runs a shipped spec (``startrack/analysis/campaign/specs/``) through the campaign
engine (``seed_campaign.py``) and prints its reference tables; the per-trial logic lives in the
campaign levels ``streak``, ``rso`` and ``smear`` (``startrack.analysis.campaign.levels``) and the
scenes in ``startrack.analysis.streak_scenes`` / ``startrack.analysis.rso_passes``. Conditions
and results: ``docs/seed_tables_001_004.md``.

1. Seed 001 Table 3.1 (``seed001-table3.1-streak-endpoints``): endpoint error (px) and rate
   error (% of |omega|) of the Harris, minimum-eigenvalue, Trajkovic-4 and Trajkovic-8 endpoint
   detectors at 10 % and 50 % streak length, spin axes 30-90 deg from the boresight, each
   detector's bias calibrated on separate frames.
2. Seed 001 Tables 4.1 and 4.2 (``seed001-tables4.1-4.2-catalog-free-rate``): catalog-free rate,
   T = 0.5 s, 2 deg/s and 0.05 rad/s about the camera y axis, with and without an Mv-1 RSO.
3. Seed 001 Tables 4.3 and 4.4 (``seed001-tables4.3-4.4-rso-detection``): RSO detections of the
   three indicators over the observation opportunities of the Table 4.3 orbits.
4. Seed 004 Table 2 (``seed004-table2-smear-centroids``): centroid error against smear
   (interstar-angle sigma and image-plane STD, microradians), StarNav I (512 x 512, 8 deg).

Usage::

    python benchmarks/streak_benchmark.py [--parts 1,2,3,4] [--frames 6] [--rso-trials 1]
        [--smear-images 30] [--seed S] [--workers 2 | --sync] [--out DIR] [--json PATH]

``--frames`` sets the frames per cell of parts 1 and 2, ``--rso-trials`` the star fields per
opportunity of part 3, ``--smear-images`` the images per cell of part 4 (the specs' own defaults
are 20, 10, 1 and 100); ``--seed`` replaces every spec's campaign seed.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import datetime
from pathlib import Path

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))

from seed_campaign import add_run_arguments, out_for, print_references, run_spec, spec_text  # noqa: E402

from startrack.analysis.campaign.aggregate import read_campaign  # noqa: E402
from startrack.analysis.campaign.reference import reference_tables  # noqa: E402

RESULTS_DIR = ROOT / "results"
PARTS = {
    1: ("seed001-table3.1-streak-endpoints", "frames"),
    2: ("seed001-tables4.1-4.2-catalog-free-rate", "frames"),
    3: ("seed001-tables4.3-4.4-rso-detection", "rso_trials"),
    4: ("seed004-table2-smear-centroids", "smear_images"),
}
"""Part -> (shipped spec, the option that sets its trials per cell)."""


def run_part(part: int, args: argparse.Namespace) -> dict:
    """Run one part's spec and print its reference tables; returns them as plain data."""
    name, option = PARTS[part]
    print(f"\npart {part}: {name}", flush=True)
    text = spec_text(name, trials=getattr(args, option), seed=args.seed)
    _, out, _ = run_spec(text, out_for(args, name), args.workers, args.sync)
    print_references(out)
    manifest, trials = read_campaign(out)
    return {"spec": name, "out": str(out), "trials_per_cell": manifest["trials_per_cell"],
            "references": [{"title": r.title, "metric": r.metric, "unit": r.unit, "rows": r.table.to_pylist()}
                           for r in reference_tables(trials, manifest, strict=False)]}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", type=str, default="1,2,3,4", help="comma-separated parts to run (1-4)")
    parser.add_argument("--frames", type=int, default=6, help="frames per cell of parts 1 and 2")
    parser.add_argument("--rso-trials", type=int, default=1, help="star fields per opportunity of part 3")
    parser.add_argument("--smear-images", type=int, default=30, help="images per cell of part 4 (seed: 100)")
    parser.add_argument("--seed", type=int, default=None, help="campaign seed of every part (default: the specs')")
    parser.add_argument("--json", type=Path, default=None, help="where to save the tables (default: results/)")
    add_run_arguments(parser)
    args = parser.parse_args(argv)
    try:
        parts = sorted({int(p) for p in args.parts.split(",")})
    except ValueError:
        parser.error(f"--parts: comma-separated numbers 1-4, got {args.parts!r}")
    if not set(parts) <= set(PARTS):
        parser.error(f"--parts: valid parts are 1-4, got {args.parts!r}")
    t0 = time.perf_counter()
    results = {"args": {k: str(v) if isinstance(v, Path) else v for k, v in vars(args).items()},
               "parts": {part: run_part(part, args) for part in parts}}
    path = args.json or RESULTS_DIR / f"streak-{datetime.now():%Y%m%d-%H%M%S}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(results, indent=1, default=str))
    print(f"\nfinished in {time.perf_counter() - t0:.0f} s; tables saved to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
