"""The lost-in-space matching trade of Jacobs 1995 (§3.5, Tables 3-5 / 3-6 / 3-7) reproduced with
our van Bezooijen matcher and our default solver.

Runs the shipped spec ``jacobs1995-tables3-5-3-7-matching`` (level ``groupmatch``, whose docstring
and ``docs/seed_tables_huffman_jacobs_samaan.md`` give the attitude region, the star lists, the guide
catalogues and the four methods: ``vb-sub``, ``vb-group``, ``vb-allsky``, ``quads``) and prints
the size of the rebuilt sub-catalogue beside the seed's, then the reference tables: success,
wrong matches, failures with fewer / more than 3 stars, average and longest match time, each
beside the seed's row.

Usage::

    python benchmarks/jacobs1995_matching.py [--trials 200] [--seed N] [--timeout-s 5]
        [--workers 2 | --sync] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from seed_campaign import add_run_arguments, out_for, print_references, run_spec, spec_text  # noqa: E402

from startrack.analysis.campaign.levels._sunsat import guides  # noqa: E402

SPEC = "jacobs1995-tables3-5-3-7-matching"
SEED_SUBCATALOGUE = {"stars": 540, "pairs": 16281}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=None, help="attitudes per cell (spec: 200; seed: 1000)")
    parser.add_argument("--seed", type=int, default=None, help="campaign seed (default: the spec's)")
    parser.add_argument("--timeout-s", type=float, default=None, help="van Bezooijen time limit per list (spec: 5)")
    add_run_arguments(parser)
    args = parser.parse_args(argv)
    g = guides()
    print(f"sub-catalogue: {len(g.sub.vectors)} stars, {len(g.sub.pairs)} pairs (seed: {SEED_SUBCATALOGUE['stars']}, "
          f"{SEED_SUBCATALOGUE['pairs']}); all-sky V <= 6: {len(g.full.vectors)} stars, {len(g.full.pairs)} pairs",
          flush=True)
    base = {} if args.timeout_s is None else {"timeout_s": args.timeout_s}
    _, out, _ = run_spec(spec_text(SPEC, trials=args.trials, seed=args.seed, base=base), out_for(args, SPEC),
                         args.workers, args.sync)
    print_references(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
