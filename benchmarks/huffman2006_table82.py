"""Huffman 2006 Table 8.2: time to match a 14-frame sequence, by matching method, ours beside the seed's.

Runs the shipped spec ``huffman2006-table8.2-sequence-matching`` (level ``seqmatch``; the seed's
conditions and ours in ``docs/seed_tables_huffman_jacobs_samaan.md``): per method, sequences of 14 simulated
frames (1024 x 1024 px, 15 deg, generic CMOS sensor, 0.2 deg/s about a random axis, one frame
per second), each detected, then matched frame to frame (``triangle``, ``rate``, chained from a
``quads`` solve of frame 0) or lost-in-space on every frame (``nvertex-3/4/5``, ``quads``).
Printed: the spec's reference tables (mean time per sequence, detection included, beside the
seed's Matlab totals; frames solved; the error at the last frame), then the ranking of the
methods by mean time, ours and the seed's.

Usage::

    python benchmarks/huffman2006_table82.py [--trials 10] [--seed N] [--workers 2 | --sync] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

sys.path.insert(0, str(Path(__file__).resolve().parent))

from seed_campaign import add_run_arguments, out_for, print_references, run_spec, spec_text  # noqa: E402

SPEC = "huffman2006-table8.2-sequence-matching"
SEED_TOTAL_S = {"triangle": 9.06, "rate": 15.12, "nvertex-3": 8.30, "nvertex-4": 8.27, "nvertex-5": 8.33}
"""Huffman 2006 Table 8.2 (Matlab, 14 frames, threshold + centroid + match + QUEST), for the ranking."""


def ranking(trials: pa.Table) -> str:
    """The seed's methods by mean sequence time, fastest first: ours, then the seed's."""
    mean = {m: float(np.mean(trials.filter(pc.equal(trials["match_method"], m))["time_s"].to_numpy()))
            for m in SEED_TOTAL_S}
    ours = " < ".join(sorted(mean, key=mean.get))
    seed = " < ".join(sorted(SEED_TOTAL_S, key=SEED_TOTAL_S.get))
    return f"ranking, fastest first: ours {ours}; seed {seed}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=None, help="sequences per method (spec: 10)")
    parser.add_argument("--seed", type=int, default=None, help="campaign seed (default: the spec's)")
    add_run_arguments(parser)
    args = parser.parse_args(argv)
    _, out, trials = run_spec(spec_text(SPEC, trials=args.trials, seed=args.seed), out_for(args, SPEC),
                              args.workers, args.sync)
    print_references(out)
    print(ranking(trials))
    return 0


if __name__ == "__main__":
    sys.exit(main())
