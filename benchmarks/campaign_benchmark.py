"""Campaign throughput: trials per second serially and on a local Dask cluster, in the same run.

    python benchmarks/campaign_benchmark.py [--workers 2] [--stars-trials 4000] [--image-trials 240]

For the "stars" level (star lists + lost-in-space, FOV 15 deg, 1024 x 1024) and the "image" level
(render 1024 x 1024, detect, solve), the same campaign runs in this process (``sync``, before and
after the others, averaged: the speed of a shared machine drifts), and on a new local cluster of
``--workers`` single-threaded worker processes. Printed per level: trials per second of each
(trials over the time from the first chunk to the last result; warming, which loads the catalog
and database and compiles the kernels once per process, is timed apart), their ratio (target at
least 1.8 on 2 cores), the machine's own ceiling for that ratio (the same trials split over
``--workers`` plain processes that each run their share serially at the same time, with no Dask:
caches and memory shared by the cores slow each of them), the scheduler overhead (the share of the
workers' time not spent inside trials: 1 - sum(trial wall time) / (workers x compute time); target
under 5 %), each worker's resident memory after the run, and whether the two trial tables agree
(times aside)."""

from __future__ import annotations

import argparse
import concurrent.futures
import multiprocessing
import os
import sys
import tempfile
from pathlib import Path

import pyarrow.compute as pc

from startrack.analysis.campaign._engine import dask_client, run_dask
from startrack.analysis.campaign._rerun import rows_agree
from startrack.analysis.campaign._run import default_chunk_size, run_campaign
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign._store import CampaignStore
from startrack.analysis.campaign._trials import plan_chunks

SPECS = {
    "stars": """
[campaign]
name = "bench-stars"
level = "stars"
trials = {trials}
seed = {seed}
[base]
fov_deg = 15.0
max_mag = 6.5
centroid_sigma_px = 0.2
false_stars = 2
""",
    "image": """
[campaign]
name = "bench-image"
level = "image"
trials = {trials}
seed = {seed}
[base]
fov_deg = 15.0
width = 1024
height = 1024
""",
}


def _rss_mib() -> float:
    import psutil

    return psutil.Process().memory_info().rss / 2**20


def serial(text: str, folder: Path) -> tuple[dict, object]:
    table = run_campaign(text, folder, sync=True, report=False)
    run = CampaignStore(folder).read_manifest()["runs"][-1]
    return run, table


def parallel(text: str, folder: Path, workers: int) -> tuple[dict, object, list[float]]:
    spec = parse_spec(text)
    store = CampaignStore(folder)
    store.trials_dir.mkdir(parents=True)
    chunks = plan_chunks(spec.cells(), spec.trials, default_chunk_size(spec, workers))
    with dask_client(workers=workers) as client:
        timings = run_dask(client, spec, chunks, lambda c, t: store.write_part(c, t))
        memory = sorted(client.run(_rss_mib).values())
    return {**timings, "workers": workers}, store.read_trials(), memory


def _share(args: tuple[str, str]) -> float:
    """Run one plain process's share of the trials serially; its compute seconds."""
    text, folder = args
    return serial(text, Path(folder))[0]["compute_s"]


def plain_processes(level: str, trials: int, workers: int, folder: Path) -> float:
    """Trials per second of ``workers`` plain processes, each running trials / workers of the
    level serially (own seed) at the same time: the machine's parallel ceiling."""
    share = max(1, trials // workers)
    jobs = [(SPECS[level].format(trials=share, seed=k + 1), str(folder / f"plain{k}"))
            for k in range(workers)]
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        seconds = list(pool.map(_share, jobs))
    return share * workers / max(seconds)


def same_trials(a, b) -> bool:
    return all(rows_agree(x, y) for x, y in zip(a.to_pylist(), b.to_pylist(), strict=True))


def measure(level: str, trials: int, workers: int) -> dict:
    text = SPECS[level].format(trials=trials, seed=1)
    with tempfile.TemporaryDirectory() as tmp:
        one, table_one = serial(text, Path(tmp) / "serial")
        many, table_many, memory = parallel(text, Path(tmp) / "dask", workers)
        plain_tps = plain_processes(level, trials, workers, Path(tmp))
        again, _ = serial(text, Path(tmp) / "serial-again")  # the machine's speed drifts: serial before and after
    busy = float(pc.sum(table_many["wall_s"]).as_py())
    return {"level": level, "trials": trials, "serial_tps": 2 * trials / (one["compute_s"] + again["compute_s"]),
            "dask_tps": trials / many["compute_s"], "plain_tps": plain_tps,
            "overhead": 1.0 - busy / (workers * many["compute_s"]),
            "warm_serial_s": one["warm_s"], "warm_dask_s": many["warm_s"], "memory": memory,
            "same": same_trials(table_one, table_many), "solved": float(pc.mean(table_one["correct"]).as_py())}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    parser.add_argument("--stars-trials", type=int, default=4000)
    parser.add_argument("--image-trials", type=int, default=240)
    args = parser.parse_args(argv)
    rows = [measure("stars", args.stars_trials, args.workers), measure("image", args.image_trials, args.workers)]
    print(f"\nlocal cluster of {args.workers} workers on {os.cpu_count()} cores; load average "
          f"{os.getloadavg()[0]:.2f} at the end")
    print(f"{'level':<6} {'trials':>6} {'serial/s':>9} {'dask/s':>8} {'ratio':>6} {'ceiling':>8} {'overhead':>9} "
          f"{'warm 1 / dask s':>16} {'MiB per worker':>16} {'same':>5} {'correct':>8}")
    for r in rows:
        mem = "/".join(f"{m:.0f}" for m in r["memory"])
        print(f"{r['level']:<6} {r['trials']:>6} {r['serial_tps']:>9.1f} {r['dask_tps']:>8.1f} "
              f"{r['dask_tps'] / r['serial_tps']:>6.2f} {r['plain_tps'] / r['serial_tps']:>8.2f} "
              f"{100 * r['overhead']:>8.1f}% "
              f"{r['warm_serial_s']:>7.2f} / {r['warm_dask_s']:<6.2f} {mem:>16} {'yes' if r['same'] else 'NO':>5} "
              f"{100 * r['solved']:>7.1f}%")
    print("ratio = dask trials/s over serial trials/s (target >= 1.8 on 2 cores); ceiling = the same ratio for "
          "plain processes running their shares at once, no Dask; overhead = 1 - trial time / (workers x compute "
          "time) (target < 5 %)")
    return 0 if all(r["same"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
