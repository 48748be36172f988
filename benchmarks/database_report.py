"""What the lost-in-space pattern database costs: build time, size on disk, load time, memory.

Ours is built from scratch in a fresh temporary ``STARTRACK_CACHE_DIR`` (so nothing cached is
reused) and then loaded in a second fresh process; both run as subprocesses of this script so
that the memory figures are clean. Build time excludes reading the Hipparcos catalog, which is
timed separately. Memory once loaded is given two ways: the growth of the process's resident set
size (RSS) across the load, and the bytes held by the database's arrays.

cedar-solve's shipped database is reported beside it (file size, load time, RSS growth), loaded
in its own environment by ``peers/cedar_runner.py``.

Usage::

    python benchmarks/database_report.py [--fov-range 3 100] [--no-peer]

The default range is startrack's default search (3-100 deg); ``--fov-range 5 35`` reports the
database the earlier default used.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def rss_bytes() -> int:
    """Resident set size of this process (Linux ``/proc``; 0 elsewhere)."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return 0


# --- the wiring to startrack: the only two functions that know its database API -----------------
def _settings(fov_min_deg: float, fov_max_deg: float):
    from startrack.identify import DatabaseSettings

    return DatabaseSettings(fov_min_deg=fov_min_deg, fov_max_deg=fov_max_deg)


def build_worker(fov_min_deg: float, fov_max_deg: float) -> dict:
    """In a fresh cache: read the catalog, then build and save the database (timed apart)."""
    from startrack.catalog import load_catalog
    from startrack.identify import database_report

    t0 = time.perf_counter()
    load_catalog()
    catalog_s = time.perf_counter() - t0
    report = database_report(_settings(fov_min_deg, fov_max_deg))
    return {"catalog_s": catalog_s, **report}


def load_worker(fov_min_deg: float, fov_max_deg: float) -> dict:
    """In a fresh process with the database cached: load it; time and RSS growth."""
    from startrack.catalog import load_catalog
    from startrack.identify import load_database

    load_catalog()
    settings = _settings(fov_min_deg, fov_max_deg)
    rss0 = rss_bytes()
    t0 = time.perf_counter()
    db = load_database(settings)
    load_s = time.perf_counter() - t0
    return {"load_s": load_s, "rss_delta_bytes": rss_bytes() - rss0, "array_bytes": db.nbytes}


# --- driving the workers ------------------------------------------------------------------------
def _run_worker(kind: str, fov_range_deg: tuple[float, float], cache: Path) -> dict:
    env = {**os.environ, "STARTRACK_CACHE_DIR": str(cache)}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", kind,
           "--fov-range", *(str(v) for v in fov_range_deg)]
    done = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def report_database(fov_range_deg: tuple[float, float] = (3.0, 100.0)) -> dict:
    """Build our pattern database for ``fov_range_deg`` in a fresh cache, load it, measure both.

    Returns a dict with ``build_s``, ``catalog_s``, ``file_bytes``, ``n_patterns``, ``n_stars``,
    ``load_s`` (fresh process), ``rss_delta_bytes`` and ``array_bytes`` (memory once loaded).
    """
    with tempfile.TemporaryDirectory(prefix="startrack-dbbench-") as tmp:
        cache = Path(tmp)
        built = _run_worker("build", fov_range_deg, cache)
        loaded = _run_worker("load", fov_range_deg, cache)
        files = {p.name: p.stat().st_size for p in cache.iterdir()}
    built.pop("load_s", None)
    return {"fov_range_deg": list(fov_range_deg), **built, **loaded, "cache_files": files}


def report_cedar_database() -> dict:
    """cedar-solve's shipped database: properties, file size, load time, RSS growth."""
    sys.path.insert(0, str(HERE))
    from methods import save_for_peer
    from peers.cedar_env import run_cedar

    with tempfile.TemporaryDirectory() as tmp:
        lists = save_for_peer([], Path(tmp) / "none.npz", width=2, height=2,
                              fov_estimate_deg=None, fov_max_error_deg=None)
        return run_cedar(lists, Path(tmp) / "out.npz")["database"]


def print_report(ours: dict | None, cedar: dict | None) -> None:
    mib = 1024.0**2
    print(f"{'database':<28} {'FOV deg':>9} {'build s':>8} {'file MiB':>9} {'load s':>7} "
          f"{'RSS MiB':>8} {'arrays MiB':>10} {'patterns':>9} {'stars':>7}")
    if ours is not None:
        lo, hi = ours["fov_range_deg"]
        print(f"{'startrack':<28} {f'{lo:g}-{hi:g}':>9} {ours['build_s']:>8.1f} "
              f"{ours['file_bytes'] / mib:>9.1f} {ours['load_s']:>7.2f} "
              f"{ours['rss_delta_bytes'] / mib:>8.1f} {ours['array_bytes'] / mib:>10.1f} "
              f"{ours['n_patterns']:>9} {ours['n_stars']:>7}")
        print(f"  (catalog read {ours['catalog_s']:.2f} s, not in the build time)")
        print("  levels (FOV deg: patterns): " + ", ".join(f"{fov:.1f}: {n}" for fov, n in ours.get("levels", [])))
    if cedar is not None:
        fov = f"{cedar['min_fov']:g}-{cedar['max_fov']:g}"
        print(f"{'cedar-solve default_database':<28} {fov:>9} {'shipped':>8} "
              f"{cedar['file_bytes'] / mib:>9.1f} {cedar['load_s']:>7.2f} "
              f"{cedar['rss_delta_bytes'] / mib:>8.1f} {'':>10} {cedar['num_patterns']:>9} "
              f"{cedar['num_stars']:>7}")
        print(f"  (cedar-solve: stars to mag {cedar['star_max_magnitude']:.2f}, "
              f"catalog {cedar['star_catalog']}, proper motion to {cedar['epoch_proper_motion']})")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fov-range", type=float, nargs=2, default=[3.0, 100.0],
                        metavar=("LO", "HI"))
    parser.add_argument("--no-peer", action="store_true")
    parser.add_argument("--no-ours", action="store_true")
    parser.add_argument("--worker", choices=["build", "load"], help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    fov_range = (args.fov_range[0], args.fov_range[1])
    if args.worker:
        worker = build_worker if args.worker == "build" else load_worker
        print(json.dumps(worker(*fov_range), default=float))
        return 0
    ours = None if args.no_ours else report_database(fov_range)
    cedar = None if args.no_peer else report_cedar_database()
    print_report(ours, cedar)
    return 0


if __name__ == "__main__":
    sys.exit(main())
