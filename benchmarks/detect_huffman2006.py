"""Huffman 2006 reproductions: WS versus MLE (Table 4.2) and pre-filter time against k (Table 7.2).

Both run as campaigns of their shipped specs (the experiment lives in the campaign levels;
``docs/seed_tables_huffman_jacobs_samaan.md`` describes the conditions and where ours differ):

1. **Table 4.2**, spec ``huffman2006-table4.2-ws-vs-mle`` (level ``centroid``): images of 30 stars
   of one magnitude M_V = 1..5 with the Table 4.1 camera, centroided by the weighted sum and by
   the maximum-likelihood fit with the PSF width known; detection time and per-axis centroid
   error beside the seed's Matlab times. Also printed: the MLE / WS time ratio per magnitude
   (the seed's 14-64).
2. **Table 7.2**, spec ``huffman2006-table7.2-prefilter-speed`` (level ``prefilter``): the 5 x 5
   pre-filter's time against the single-pixel threshold k = 1, 1.5, 2, 3, 4 for the
   per-candidate window form (``starCentroid2``) and the grid form (``starCentroid3``), on 14
   frames of a slow pass with the FAR-MST camera, and the stars centroided.

    .venv/bin/python benchmarks/detect_huffman2006.py [--images 20] [--frames 14] [--seed N]
        [--workers 2 | --sync] [--out DIR]
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

TABLE_42 = "huffman2006-table4.2-ws-vs-mle"
TABLE_72 = "huffman2006-table7.2-prefilter-speed"
SEED_TIMES_42 = {1.0: (5.74, 81.07), 2.0: (5.10, 77.57), 3.0: (2.81, 74.56), 4.0: (1.61, 67.60), 5.0: (0.73, 46.78)}
"""Huffman 2006 Table 4.2 (WS s, MLE s per 30-star image, Matlab), for the ratio line."""


def time_ratios(trials: pa.Table) -> list[str]:
    """MLE / WS median detection time per magnitude, ours beside the seed's."""
    lines = ["MLE / WS time per image:  M_V   ours   seed"]
    for mag, (ws, mle) in SEED_TIMES_42.items():
        ours = [float(np.median(trials.filter(pc.and_(pc.equal(trials["mag_v"], mag),
                                                      pc.equal(trials["detect_centroid"], c)))["time_s"]))
                for c in ("weighted", "mle")]
        lines.append(f"{'':>26}{mag:4g}{ours[1] / ours[0]:7.2f}{mle / ws:7.1f}")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", type=int, default=None, help="images per cell of Table 4.2 (spec: 20)")
    parser.add_argument("--frames", type=int, default=None, help="frames per cell of Table 7.2 (spec: 14)")
    parser.add_argument("--seed", type=int, default=None, help="campaign seed (default: the specs')")
    add_run_arguments(parser)
    args = parser.parse_args(argv)
    for name, trials in ((TABLE_42, args.images), (TABLE_72, args.frames)):
        _, out, table = run_spec(spec_text(name, trials=trials, seed=args.seed), out_for(args, name),
                                 args.workers, args.sync)
        print_references(out)
        if name == TABLE_42:
            print("\n".join(time_ratios(table)))
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
