"""The browser tool's server: time from upload to result for the real images, and its memory
with 10 jobs queued.

A real ``startrack web`` server is started in a child process (the launcher of the browser
tests, ``tests/web/web_server.py``) on a temporary data folder, with one worker, and waited for
until its worker is ready (catalog and default pattern database loaded). Then:

- **upload to result**: each real image of ``../shared/realdata`` (truth.csv) is posted to
  ``POST /api/jobs`` with no options (the FOV is searched over the solver's default range) and ``GET /api/jobs/{id}``
  is polled every 10 ms until the job ends; the time is the wall clock of the client from the
  start of the upload to the answer that says ``done`` (or ``failed``). ``--repeats`` posts each
  image that many times and prints the median. The worker's own per-stage times are printed
  beside it (read, detect, identify, attitude, refine, annotate: the annotated frame and the
  result files).
- **memory**: the resident set size (``/proc``, via psutil) of the server process, of the fork
  server that holds the preloaded catalog and database, and of the worker, idle and then with
  one slow job running and 10 more queued (all cancelled afterwards).

Usage::

    python benchmarks/web_benchmark.py [--repeats 3] [--workers 1]
"""

from __future__ import annotations

import argparse
import csv
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import psutil

ROOT = Path(__file__).resolve().parents[1]
REALDATA = ROOT.parent / "shared" / "realdata"
sys.path.insert(0, str(ROOT / "tests" / "web"))
from web_server import WebServer  # noqa: E402  (the launcher the browser tests use)

from startrack.identify._registry import DEFAULT_FOV_RANGE_DEG  # noqa: E402
from startrack.io import write_png  # noqa: E402

SLOW = {"method": "pyramid", "fov_deg": 10.0}


def upload_to_result(server: WebServer, path: Path) -> tuple[float, dict]:
    """Seconds from the start of the upload to the answer that says the job ended, and the job."""
    t0 = time.perf_counter()
    job_id = server.submit(path).json()["id"]
    while True:
        job = server.client.get(f"/api/jobs/{job_id}").json()
        if job["state"] in ("done", "failed", "cancelled"):
            return time.perf_counter() - t0, job
        time.sleep(0.01)


def image_table(server: WebServer, repeats: int) -> None:
    with open(REALDATA / "truth.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    lo, hi = DEFAULT_FOV_RANGE_DEG
    print(f"\nupload to result, {repeats} run(s) per image, median (one worker, FOV searched {lo:g}-{hi:g} deg)")
    print(f"{'image':<16}{'size':>11}{'state':>7}{'matched':>9}{'total s':>9}   worker stages, s "
          "(read detect identify attitude refine annotate)")
    for row in rows:
        path = REALDATA / row["set"] / row["file"]
        runs = [upload_to_result(server, path) for _ in range(repeats)]
        total = statistics.median(t for t, _ in runs)
        job = runs[-1][1]
        result = job["result"] or {}
        stages = " ".join(f"{job['times_s'].get(s, float('nan')):.3f}"
                          for s in ("read", "detect", "identify", "attitude", "refine", "annotate"))
        print(f"{row['file']:<16}{row['width'] + 'x' + row['height']:>11}{job['state']:>7}"
              f"{result.get('n_matched', 0):>9}{total:>9.3f}   {stages}")


def random_field(folder: Path) -> Path:
    """A frame of random spots that no sky matches: with :data:`SLOW` a job of at least 5 s."""
    rng = np.random.default_rng(1)
    yy, xx = np.mgrid[0:512, 0:512]
    image = rng.normal(100.0, 3.0, (512, 512))
    for x, y, a in zip(rng.uniform(10, 502, 60), rng.uniform(10, 502, 60), rng.uniform(200, 3000, 60), strict=True):
        image += a * np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * 1.2**2))
    path = folder / "random_field.png"
    write_png(path, np.clip(image, 0, 65535).astype(np.uint16))
    return path


def rss_mb(server: WebServer) -> dict[str, float]:
    """Resident memory of the server, the fork server and the workers (RSS, and for the workers
    also USS: the pages no other process shares, what a worker costs beyond the fork server), MB."""
    main = psutil.Process(server.process.pid)
    workers = {w["pid"] for w in server.client.get("/api/status").json()["workers"]}
    out = {"server": main.memory_info().rss / 1e6, "fork server": 0.0, "workers": 0.0, "workers uss": 0.0}
    for child in main.children(recursive=True):
        try:
            info = child.memory_full_info()
            cmdline = " ".join(child.cmdline())
        except psutil.NoSuchProcess:
            continue
        if child.pid in workers:
            out["workers"] += info.rss / 1e6
            out["workers uss"] += info.uss / 1e6
        elif "forkserver" in cmdline:
            out["fork server"] += info.rss / 1e6
    return out


def memory_table(server: WebServer, folder: Path) -> None:
    idle = rss_mb(server)
    slow = server.submit(random_field(folder), SLOW).json()["id"]
    server.wait_job(slow, states=("running",))
    queued = [server.submit(REALDATA / "smroid-cedar-solve" / "roof.jpg").json()["id"] for _ in range(10)]
    status = server.client.get("/api/status").json()
    busy = rss_mb(server)
    for job_id in [*queued, slow]:
        server.client.delete(f"/api/jobs/{job_id}")
    print(f"\nresident memory, MB (psutil RSS); {status['queued']} jobs queued and 1 running in the second row")
    print(f"{'':<22}{'server':>9}{'fork server':>13}{'workers':>9}{'workers USS':>13}")
    for label, mem in (("idle", idle), ("10 queued + 1 running", busy)):
        print(f"{label:<22}{mem['server']:>9.1f}{mem['fork server']:>13.1f}{mem['workers']:>9.1f}"
              f"{mem['workers uss']:>13.1f}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per image (default 3)")
    parser.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    args = parser.parse_args()
    if not (REALDATA / "truth.csv").is_file():
        print(f"the real images are not at {REALDATA}; nothing to measure")
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        server = WebServer(Path(tmp) / "data", "--workers", str(args.workers), "--max-queued", "32")
        try:
            server.wait_ready()
            print(f"server started and its worker ready in {time.perf_counter() - t0:.1f} s")
            image_table(server, args.repeats)
            memory_table(server, Path(tmp))
        finally:
            server.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
