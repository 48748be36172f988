"""Lost-in-space benchmark on seeded random star lists: startrack side by side with cedar-solve.

For each field of view, ``--trials`` star lists are generated (:mod:`starlists`: random
attitudes, centroid noise 0.1-0.5 px, 0-20 % missing stars, 0-6 false stars, magnitude noise) and
solved by both methods in the same run, first with the FOV known, then with only a FOV range
(``--fov-range``), and with ``--no-hint`` also with nothing said about the FOV (each solver's
default search: startrack's 3-100 deg, cedar-solve's whole database). Printed per method and
condition: success rate, false-solve rate, median and
95th-percentile solve time, and for startrack the ratio of its times to cedar-solve's. The
methods take turns on chunks of ``--interleave`` lists, so a drift of the machine's speed during
a long run (seen on shared VMs) does not favour whichever ran first.
Results (the table and per-trial arrays) are saved as JSON under ``benchmarks/results/``.

``--easy`` replaces the lists by easy ones: the 25 brightest stars, 0.1 px of noise, none
missing, no false stars, no magnitude noise. ``--clock cpu`` times every solve (ours and
cedar-solve's) by the CPU time of the solving thread (``time.thread_time``) instead of the wall
clock, so that other work on a shared machine does not count; ``--pin`` runs startrack on CPU 0
and cedar-solve on CPU 1 (Linux affinity, the peer process inherits it). ``--stages`` splits
startrack's CPU time per solve into its stages (request, look-up, confirmation, final fit and
its refits and re-matches, covariance, the rest of building the solution) and prints the
medians. The load average before and after is printed under the table.

Usage::

    python benchmarks/lis_benchmark.py [--trials 300] [--seed 1] [--fov-deg 10 15 20]
                                       [--fov-range 5 35] [--no-range] [--no-hint] [--no-peer]
                                       [--interleave 1000] [--easy] [--clock {wall,cpu}] [--pin]
                                       [--stages]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import platform
import sys
import time
from datetime import datetime
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import methods  # noqa: E402
from methods import FovKnowledge, MethodRun, concatenate_runs, solve_cedar, solve_ours  # noqa: E402

from startrack.analysis._scoring import (  # noqa: E402
    TOLERANCE_PIXELS,
    attitude_errors_rad,
    boresight_and_roll_errors,
    roll_weight,
    summarize,
    tolerance_rad,
)
from startrack.analysis._starlists import Conditions, generate_star_lists, load_sky  # noqa: E402
from startrack.identify._registry import MATCHERS  # noqa: E402
from startrack.units import ARCSEC  # noqa: E402

LIS_MATCHERS = [name for name in MATCHERS if name != "overlay"]

RESULTS_DIR = Path(__file__).resolve().parent / "results"
HEADER = (f"{'method':<22} {'condition':<25} {'trials':>6} {'success':>8} {'false #':>7} "
          f"{'median ms':>10} {'p95 ms':>8} {'p99 ms':>8} {'x cedar med':>11} {'x cedar p95':>11} {'x cedar p99':>11} "
          f"{'db MiB':>7}")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=300, help="star lists per FOV (default 300)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--fov-deg", type=float, nargs="+", default=[10.0, 15.0, 20.0])
    parser.add_argument("--fov-range", type=float, nargs=2, default=[5.0, 35.0],
                        metavar=("LO", "HI"),
                        help="FOV range given to the solvers in the unknown-FOV runs (deg)")
    parser.add_argument("--no-range", action="store_true", help="only run with the FOV known")
    parser.add_argument("--no-known", action="store_true", help="do not run with the FOV known")
    parser.add_argument("--no-hint", action="store_true",
                        help="also run with no FOV given (the solvers' default search)")
    parser.add_argument("--no-peer", action="store_true", help="do not run cedar-solve")
    parser.add_argument("--no-ours", action="store_true", help="do not run startrack")
    parser.add_argument("--matchers", nargs="+", default=["quads"], choices=LIS_MATCHERS,
                        help="startrack matchers to run (all but quads only where the FOV is known)")
    parser.add_argument("--cedar-timeout-ms", type=float, default=5000.0)
    parser.add_argument("--timeout-s", type=float, default=None,
                        help="time limit of startrack's matchers (default: each matcher's own, 5 s)")
    parser.add_argument("--interleave", type=int, default=1000,
                        help="methods take turns on chunks of this many lists (default 1000)")
    parser.add_argument("--progress", type=int, default=100, help="progress line every N trials")
    parser.add_argument("--easy", action="store_true",
                        help="easy lists: the 25 brightest stars, 0.1 px noise, none missing or false")
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                        help="time solves by the wall clock (default) or the solving thread's CPU time")
    parser.add_argument("--pin", action="store_true", help="startrack on CPU 0, cedar-solve on CPU 1")
    parser.add_argument("--stages", action="store_true",
                        help="print the median CPU time of startrack's stages per solve")
    parser.add_argument("--out", type=Path, default=None,
                        help="JSON file (default: results/lis-*.json)")
    return parser.parse_args(argv)


def knowledge_list(fov_deg: float, args: argparse.Namespace) -> list[FovKnowledge]:
    out = [] if args.no_known else [FovKnowledge(fov_deg=fov_deg)]
    if not args.no_range:
        out.append(FovKnowledge(fov_range_deg=(args.fov_range[0], args.fov_range[1])))
    if args.no_hint:
        out.append(FovKnowledge())
    return out


def run_methods(lists, conditions, knowledge, args, skip_ours: str | None) -> list[MethodRun]:
    """Every method on the lists, taking turns on chunks of ``args.interleave`` lists (so that a
    drift of the machine's speed during the run touches every method alike)."""
    size = max(1, args.interleave)
    chunks = [lists[i:i + size] for i in range(0, len(lists), size)]
    per_chunk = []
    for k, chunk in enumerate(chunks):
        print(f"{conditions.name}, {knowledge.label}: lists {k * size}-{k * size + len(chunk) - 1} "
              f"of {len(lists)}", file=sys.stderr, flush=True)
        per_chunk.append(_run_chunk(chunk, conditions, knowledge, args, skip_ours))
    return [concatenate_runs(list(runs)) for runs in zip(*per_chunk, strict=True)]


def _run_chunk(lists, conditions, knowledge, args, skip_ours: str | None) -> list[MethodRun]:
    runs = []
    for matcher in ([] if skip_ours else args.matchers):
        if matcher != "quads" and knowledge.fov_deg is None:
            continue  # the pair-directory matchers need a known field of view
        with _on_cpu(0 if args.pin else None):
            runs.append(solve_ours_measured(lists, conditions, knowledge, args, matcher))
    if not args.no_peer:
        with _on_cpu(1 if args.pin else None):
            runs.append(solve_cedar(lists, conditions, knowledge, timeout_ms=args.cedar_timeout_ms,
                                    progress=args.progress, clock=args.clock))
    return runs


@contextlib.contextmanager
def _on_cpu(cpu: int | None):
    """This process (and the processes it starts) on one CPU while inside (None: unchanged)."""
    if cpu is None or not hasattr(os, "sched_setaffinity"):
        yield
        return
    saved = os.sched_getaffinity(0)
    os.sched_setaffinity(0, {cpu % os.cpu_count()})
    try:
        yield
    finally:
        os.sched_setaffinity(0, saved)


def _loaded_tables() -> set:
    """(kind, settings) of every cached table loaded in this process so far."""
    from startrack.identify import _database as database
    from startrack.identify import _pair_database as pair_database
    from startrack.identify import _triangle_database as triangle_database

    return ({("patterns", k) for k in database._LOADED} | {("pairs", k) for k in pair_database._LOADED}
            | {("triangles", k) for k in triangle_database._LOADED})


def _table_bytes(kind: str, key) -> int:
    from dataclasses import asdict

    from startrack import cache
    from startrack.identify import _database as database
    from startrack.identify import _pair_database as pair_database
    from startrack.identify import _triangle_database as triangle_database

    if kind == "patterns":
        return database.database_path(key).stat().st_size
    if kind == "pairs":
        params, version = asdict(key), pair_database.PAIRS_VERSION
    else:
        settings, variant = key
        params = {**asdict(settings), "variant": variant, "levels": triangle_database.SUBDIVISION_LEVELS}
        version = triangle_database.TRIANGLES_VERSION
    return (cache.cache_dir() / f"{kind}-{cache.input_key(kind, version, params)}.npz").stat().st_size


_SEEN: dict[tuple, set] = {}
"""Tables each kind of matcher loaded per condition (a table loaded once is not loaded again)."""


def solve_ours_measured(lists, conditions, knowledge, args, matcher) -> MethodRun:
    """:func:`solve_ours` plus the on-disk size (MiB) of the tables the matcher loaded for it."""
    before = _loaded_tables()
    run = solve_ours(lists, conditions, knowledge, matcher=matcher, progress=args.progress,
                     timeout_s=args.timeout_s, clock=args.clock)
    new = _loaded_tables() - before
    for kind in ("patterns", "pairs"):
        key = (conditions.name, knowledge.label, kind)
        _SEEN[key] = _SEEN.get(key, set()) | {t for t in new if t[0] == kind}
    kind = "patterns" if matcher == "quads" else "pairs"
    used = _SEEN[(conditions.name, knowledge.label, kind)] | {t for t in new if t[0] == "triangles"}
    if matcher == "quads" and not used:  # loaded in an earlier condition: the default database
        used = {t for t in before if t[0] == "patterns"}
    run.extra["database_mib"] = sum(_table_bytes(k, key) for k, key in used) / 2**20
    return run


def score_runs(runs: list[MethodRun], lists, conditions: Conditions, label: str) -> list[dict]:
    """One row per method: the summary plus per-trial arrays, and the ratio to cedar-solve."""
    truths = [s.rot_cam_from_icrs for s in lists]
    tol = tolerance_rad(conditions.camera)
    rows = []
    for run in runs:
        err = attitude_errors_rad(truths, run.estimates, roll_weight(conditions.camera))
        row = {"method": run.method, "condition": f"{conditions.name} {label}", **summarize(
            run.solved, err, run.time_s, tol)}
        err_arcsec = [None if math.isnan(e) else e / ARCSEC for e in err]
        row["trials"] = {"solved": run.solved.tolist(), "time_ms": (run.time_s * 1e3).tolist(),
                         "err_arcsec": err_arcsec}
        row["p99_ms"] = float(np.percentile(run.time_s, 99) * 1e3) if run.time_s.size else math.nan
        if "roll_deg" in run.extra:
            row.update(roll_check(truths, run, err <= tol))
        row["database_mib"] = run.extra.get("database_mib", run.extra.get("database", {}).get("file_bytes", 0) / 2**20)
        rows.append(row)
    add_ratios(rows)
    return rows


def roll_check(truths, run: MethodRun, good) -> dict:
    """Median boresight error and |roll difference| (arcsec) of a peer's correct solves.

    Checks that the peer's RA / Dec / roll mean what ours do: a roll convention that differed
    would show as degrees here (and as false solves).
    """
    e = run.extra
    checks = boresight_and_roll_errors(truths, e["ra_deg"], e["dec_deg"], e["roll_deg"])
    if not np.any(good):
        return {}
    bore = np.median(checks["boresight_err_rad"][good]) / ARCSEC
    roll = np.median(np.abs(checks["roll_diff_rad"][good])) / ARCSEC
    return {"median_boresight_err_arcsec": float(bore), "median_abs_roll_diff_arcsec": float(roll)}


def add_ratios(rows: list[dict]) -> None:
    """Ours / cedar-solve for the median, 95th- and 99th-percentile times, on startrack's row."""
    peer = next((r for r in rows if r["method"] == "cedar-solve"), None)
    for row in rows:
        if peer is not None and row["method"] != "cedar-solve":
            row["ratio_median"] = row["median_ms"] / peer["median_ms"]
            row["ratio_p95"] = row["p95_ms"] / peer["p95_ms"]
            row["ratio_p99"] = row["p99_ms"] / peer["p99_ms"]


def format_row(row: dict) -> str:
    ratio = (f"{row['ratio_median']:>11.2f} {row['ratio_p95']:>11.2f} {row['ratio_p99']:>11.2f}"
             if "ratio_median" in row else f"{'':>11} {'':>11} {'':>11}")
    return (f"{row['method']:<22} {row['condition']:<25} {row['n']:>6} {row['success_rate']:>8.2%} "
            f"{round(row['false_rate'] * row['n']):>7d} {row['median_ms']:>10.2f} {row['p95_ms']:>8.2f} "
            f"{row['p99_ms']:>8.2f} {ratio} "
            f"{row.get('database_mib', 0.0):>7.1f}")


def print_table(rows: list[dict], notes: list[str]) -> None:
    print()
    print(HEADER)
    print("-" * len(HEADER))
    for row in rows:
        print(format_row(row))
    for note in notes:
        print(note)


def save_json(path: Path | None, payload: dict) -> Path:
    if path is None:
        RESULTS_DIR.mkdir(parents=True, exist_ok=True)
        path = RESULTS_DIR / f"lis-{datetime.now():%Y%m%d-%H%M%S}.json"
    path.write_text(json.dumps(payload, indent=1, default=str))
    return path


def table_notes(rows: list[dict], skip_ours: str | None, peer_db: dict | None,
                loads: tuple[float, float], args: argparse.Namespace) -> list[str]:
    """The lines printed under the table: definitions, machine load, roll check, peer database."""
    clock = ("CPU time of the solving thread (time.thread_time)" if args.clock == "cpu"
             else "wall clock (time.perf_counter)")
    notes = [f"success: attitude error < {TOLERANCE_PIXELS:g} pixel angles; false: solved outside"
             " it; times over all trials, after one warm-up solve",
             f"times: {clock}{'; startrack on CPU 0, cedar-solve on CPU 1' if args.pin else ''}",
             "x cedar: startrack's time / cedar-solve's on the same lists",
             f"load average before / after: {loads[0]:.2f} / {loads[1]:.2f} on {os.cpu_count()} "
             "cores (other work on the machine slows both methods)"]
    if skip_ours:
        notes.append(f"startrack not run: {skip_ours}")
    notes.extend(f"  {r['method']} {r['condition']}: median boresight error "
                 f"{r['median_boresight_err_arcsec']:.1f} arcsec, median |roll - true roll| "
                 f"{r['median_abs_roll_diff_arcsec']:.1f} arcsec"
                 for r in rows if "median_abs_roll_diff_arcsec" in r)
    if peer_db:
        notes.append(f"cedar-solve database: FOV {peer_db['min_fov']:g}-{peer_db['max_fov']:g} "
                     f"deg, stars to mag {peer_db['star_max_magnitude']:.2f}, "
                     f"{peer_db['num_patterns']} patterns")
    return notes


EASY = {"sigma_px_range": (0.1, 0.1), "missing_fraction_range": (0.0, 0.0), "false_stars_range": (0, 0),
        "mag_noise": 0.0, "max_stars": 25}
"""The easy lists of ``--easy``: the 25 brightest stars with 0.1 px of noise, nothing missing or false."""

STAGES = (("request", "startrack.solve", "build_request"),
          ("look-up", "startrack.identify._quad_matcher", "search_batch"),
          ("confirmation", "startrack.identify._confirm", "Confirmer.confirm"),
          ("  field cone", "startrack.identify._confirm", "field_cone"),
          ("  matches", "startrack.identify._confirm", "predicted_pairs"),
          ("  bound", "startrack.identify._confirm", "false_match_bound_counts"),
          ("final fit", "startrack.solve", "settle_matches"),
          ("  refits", "startrack.identify._final_fit", "fit_pose"),
          ("  deleted residuals", "startrack.identify._final_fit", "leave_one_out_residuals"),
          ("  catalog choice", "startrack.identify._final_fit", "_Catalog.chosen"),
          ("  re-match", "startrack.identify._final_fit", "rematch"),
          ("solution", "startrack.solve", "_solution"),
          ("  covariance", "startrack.solve", "covariance_batch"))
"""Stages of a startrack solve timed by ``--stages``: (label, module, function or Class.method);
each is timed inclusively (a stage's time holds the stages indented under it), one missing from
the code is skipped."""


class StageTimer:
    """CPU time (``time.thread_time``, s) of each of :data:`STAGES` per ``solve_stars`` call, by
    wrapping those functions while inside ``with`` (the real functions run; the wrappers only read
    the clock). ``solves`` holds one dict {label: s} per solve, with "total"."""

    def __init__(self) -> None:
        self.solves: list[dict[str, float]] = []
        self._current: dict[str, float] = {}
        self._stack = contextlib.ExitStack()

    def _timed(self, label: str, func):
        def wrapper(*a, **k):
            t0 = time.thread_time()
            try:
                return func(*a, **k)
            finally:
                self._current[label] = self._current.get(label, 0.0) + time.thread_time() - t0
        return wrapper

    def _solve(self, func):
        def wrapper(*a, **k):
            self._current = {}
            out = self._timed("total", func)(*a, **k)
            self.solves.append(self._current)
            return out
        return wrapper

    def _patch(self, owner, name: str, new) -> None:
        old = owner.__dict__[name] if isinstance(owner, type) else getattr(owner, name)
        setattr(owner, name, new)
        self._stack.callback(setattr, owner, name, old)

    def __enter__(self) -> StageTimer:
        import importlib

        self._patch(methods, "solve_stars", self._solve(methods.solve_stars))
        for label, module, name in STAGES:
            owner, *attr = [importlib.import_module(module), *name.split(".")]
            for part in attr[:-1]:
                owner = getattr(owner, part, None)
            raw = (getattr(owner, "__dict__", {}).get(attr[-1]) if isinstance(owner, type)
                   else getattr(owner, attr[-1], None))
            if raw is None:
                continue
            if isinstance(raw, classmethod):
                self._patch(owner, attr[-1], classmethod(self._timed(label, raw.__func__)))
            else:
                self._patch(owner, attr[-1], self._timed(label, raw))
        return self

    def __exit__(self, *exc) -> None:
        self._stack.close()

    def lines(self, title: str) -> list[str]:
        """The table: median and mean ms per solve of each stage, and its share of the mean total."""
        if not self.solves:
            return []
        labels = ["total"] + [label for label, _, _ in STAGES if any(label in s for s in self.solves)]
        total = np.mean([s["total"] for s in self.solves])
        out = [f"startrack stages, {title} ({len(self.solves)} solves, CPU time of the thread)",
               f"  {'stage':<22} {'median ms':>10} {'mean ms':>8} {'share':>6}"]
        for label in labels:
            values = np.array([s.get(label, 0.0) for s in self.solves])
            out.append(f"  {label:<22} {np.median(values) * 1e3:>10.3f} {values.mean() * 1e3:>8.3f} "
                       f"{values.mean() / total:>6.1%}")
        solution = np.array([s.get("solution", 0.0) - s.get("final fit", 0.0) for s in self.solves])
        out.append(f"  {'  (assembly)':<22} {np.median(solution) * 1e3:>10.3f} {solution.mean() * 1e3:>8.3f} "
                   f"{solution.mean() / total:>6.1%}")
        return out


def conditions_for(fov_deg: float, args: argparse.Namespace) -> Conditions:
    """The benchmark's lists for one field of view (the easy ones with ``--easy``)."""
    return Conditions(fov_deg=fov_deg, **(EASY if args.easy else {}))


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    skip_ours = "--no-ours given" if args.no_ours else None
    load_before = os.getloadavg()[0]
    rows: list[dict] = []
    peer_db: dict | None = None
    t0 = time.perf_counter()
    stage_lines: list[str] = []
    for fov_deg in args.fov_deg:
        conditions = conditions_for(fov_deg, args)
        lists = generate_star_lists(conditions, args.trials, args.seed, sky=load_sky(conditions))
        for knowledge in knowledge_list(fov_deg, args):
            label = f"{'easy ' if args.easy else ''}{knowledge.label}"
            with StageTimer() if args.stages else contextlib.nullcontext() as timer:
                runs = run_methods(lists, conditions, knowledge, args, skip_ours)
            stage_lines.extend(timer.lines(f"{conditions.name} {label}") if timer else [])
            peer_db = next((r.extra["database"] for r in runs if "database" in r.extra), peer_db)
            rows.extend(score_runs(runs, lists, conditions, label))
    loads = (load_before, os.getloadavg()[0])
    print_table(rows, table_notes(rows, skip_ours, peer_db, loads, args))
    for line in stage_lines:
        print(line)
    payload = {"args": vars(args), "python": platform.python_version(),
               "machine": platform.machine(), "wall_s": time.perf_counter() - t0,
               "load_average_before_after": list(loads), "cedar_database": peer_db, "rows": rows}
    print(f"results saved to {save_json(args.out, payload)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
