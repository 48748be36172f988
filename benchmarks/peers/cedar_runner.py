"""Solve star lists with cedar-solve (tetra3). Runs inside ``benchmarks/.venv-cedar`` only.

Usage::

    python cedar_runner.py LISTS.npz OUT.npz [--solve-timeout-ms 5000] [--no-warmup] [--progress N]
                           [--clock wall|cpu]

``LISTS.npz`` (written by ``starlists.save_for_peer``) holds the lists back to back in
startrack's pixel convention (0-based pixel centres, x = column): ``x``, ``y`` (brightest first),
``offsets`` (list i is ``offsets[i]:offsets[i + 1]``), per-list ``width``, ``height``,
``fov_estimate_deg`` and ``fov_max_error_deg`` (NaN means "not given", i.e. None).

This file must not import startrack (which needs numpy >= 2 features); it only converts the
centroids to tetra3's convention, (y, x) with the centre of the top-left pixel at (0.5, 0.5), and
calls ``Tetra3.solve_from_centroids`` with the shipped ``default_database``. Each solve is timed
around that call alone (process start and database load excluded) by ``--clock``: ``wall``
(``time.perf_counter``, the default) or ``cpu`` (``time.thread_time``, the solving thread's CPU time).
One untimed warm-up solve of the first list runs first unless ``--no-warmup``.

``OUT.npz`` holds per-list ``solved`` (bool), ``status`` (tetra3's code: 1 match found,
2 no match, 3 timeout, 4 cancelled, 5 too few), ``ra_deg``, ``dec_deg``, ``roll_deg``,
``fov_deg``, ``prob`` (NaN when unsolved), ``time_s``, and ``database_json`` (the database's
properties plus its file size, load time and the growth of the resident set size on loading).
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

TETRA3_PIXEL_OFFSET = 0.5  # startrack.conventions.TETRA3_PIXEL_OFFSET; kept here, see above
MATCH_FOUND = 1
RESULT_KEYS = ("ra_deg", "dec_deg", "roll_deg", "fov_deg", "prob")
TETRA3_KEYS = ("RA", "Dec", "Roll", "FOV", "Prob")
CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}


def load_tetra3():
    """The Tetra3 solver with its shipped database, quiet, and the database's description."""
    logger = logging.getLogger("tetra3.Tetra3")
    logger.addHandler(logging.NullHandler())  # keeps tetra3 from adding a console handler
    logger.setLevel(logging.WARNING)
    import tetra3

    rss0 = _rss_bytes()
    t0 = time.perf_counter()
    solver = tetra3.Tetra3("default_database")
    load_s = time.perf_counter() - t0
    rss_delta = _rss_bytes() - rss0
    db_path = Path(tetra3.__file__).parent / "data" / "default_database.npz"
    props = {k: _jsonable(v) for k, v in solver.database_properties.items()}
    props.update(file=str(db_path), file_bytes=db_path.stat().st_size, load_s=load_s,
                 rss_delta_bytes=rss_delta,
                 num_stars=int(solver.star_table.shape[0]), cedar_solve_tetra3=tetra3.__file__)
    return solver, props


def _rss_bytes() -> int:
    """Resident set size of this process (Linux ``/proc``; 0 elsewhere)."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


def _jsonable(value):
    value = value.item() if isinstance(value, np.generic) else value
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _optional(value: float) -> float | None:
    return None if not np.isfinite(value) else float(value)


def solve_one(solver, lists: dict, i: int, timeout_ms: float, clock=time.perf_counter) -> tuple[dict, float]:
    """Solve list i; return tetra3's result dict and the time of the call by ``clock``, in s."""
    lo, hi = int(lists["offsets"][i]), int(lists["offsets"][i + 1])
    yx = np.column_stack([lists["y"][lo:hi] + TETRA3_PIXEL_OFFSET,
                          lists["x"][lo:hi] + TETRA3_PIXEL_OFFSET])
    size = (int(lists["height"][i]), int(lists["width"][i]))
    kwargs = dict(fov_estimate=_optional(lists["fov_estimate_deg"][i]),
                  fov_max_error=_optional(lists["fov_max_error_deg"][i]),
                  solve_timeout=timeout_ms)
    t0 = clock()
    result = solver.solve_from_centroids(yx, size, **kwargs)
    return result, clock() - t0


def solve_all(solver, lists: dict, timeout_ms: float, warmup: bool,
              progress: int = 0, clock=time.perf_counter) -> dict[str, np.ndarray]:
    n = len(lists["offsets"]) - 1
    out = {k: np.full(n, np.nan) for k in (*RESULT_KEYS, "time_s")}
    out["status"] = np.zeros(n, dtype=np.int64)
    if warmup and n:
        solve_one(solver, lists, 0, timeout_ms)
    for i in range(n):
        if progress and i and i % progress == 0:
            print(f"  cedar-solve {i}/{n}", file=sys.stderr, flush=True)
        result, elapsed = solve_one(solver, lists, i, timeout_ms, clock)
        out["time_s"][i] = elapsed
        out["status"][i] = int(result["status"])
        if result["status"] == MATCH_FOUND:
            for ours, theirs in zip(RESULT_KEYS, TETRA3_KEYS, strict=True):
                out[ours][i] = float(result[theirs])
    out["solved"] = out["status"] == MATCH_FOUND
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Solve star lists with cedar-solve.")
    parser.add_argument("lists", type=Path)
    parser.add_argument("out", type=Path)
    parser.add_argument("--solve-timeout-ms", type=float, default=5000.0)
    parser.add_argument("--no-warmup", action="store_true")
    parser.add_argument("--progress", type=int, default=0, help="print progress every N lists")
    parser.add_argument("--clock", choices=sorted(CLOCKS), default="wall", help="how each solve is timed")
    args = parser.parse_args(argv)
    with np.load(args.lists, allow_pickle=False) as npz:
        lists = {name: npz[name] for name in npz.files}
    solver, props = load_tetra3()
    out = solve_all(solver, lists, args.solve_timeout_ms, not args.no_warmup, args.progress, CLOCKS[args.clock])
    np.savez(args.out, database_json=np.array(json.dumps(props)), **out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
