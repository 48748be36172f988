"""Where a user waits: import time, the first solve in a new process, the command's wall time for
one image and for a batch of 20, beside cedar-solve and astrometry.net, in one run.

Measured, each in fresh processes (the median of ``--repeat`` runs where it says so):

* ``import startrack`` and ``import startrack.cli._solve_cmd`` (the solve command's modules);
* the first solve in a new process once the caches exist: the database load, the warm-up
  (:func:`startrack.cli._batch_warmup.warm_up`: the compiled kernels loaded from numba's cache,
  the smallest first so that numba's own start, 0.25-0.4 s whatever function comes first, is
  printed apart from quad_kernel.search's load),
  the first and second ``solve_image`` of a real photo, and the same first solve with no warm-up
  (loading then falls inside it); and what each compiled function costs to load (numba's
  ``load_overload`` timed per function, largest first);
* ``startrack solve IMAGE`` wall and CPU time (the console script in a new process), with
  startrack's bytecode kept as an install has it (see :func:`_with_bytecode`) and, when this
  environment turned bytecode off, once more as it runs here (compiled from source);
* the floor under any command built on this stack: a new process of the same Python that imports
  numpy, ``scipy.spatial`` (where ``Rotation`` lives) and numba and calls one trivial compiled
  function from numba's cache, with nothing of startrack (:data:`STACK_FLOOR`);
* a batch of 20 real photos: ``startrack solve FOLDER`` (one process) against 20 commands one
  after the other, total and per image;
* cedar-solve (its own virtual environment, ``benchmarks/peers/cedar_env.py``): a new process
  that imports tetra3, loads its database and solves the same photo (``solve_from_image``), and
  20 photos in one such process;
* astrometry.net's ``solve-field`` on the same photo (Debian's, with its Tycho-2 index files:
  ``benchmarks/peers/astrometry_env.py`` installs them where it may, otherwise a printed note
  says why the peer was left out);
* with ``--cold``, first: the one-time compile, ``startrack warm-up`` with an empty numba cache
  (``NUMBA_CACHE_DIR`` set to a new temporary folder, so the catalog and databases stay cached);
  the rest then runs on that fresh numba cache, as after an install (a development cache holds
  the stale files of every edited kernel; :func:`startrack.numba_cache.heal` reads only the files
  that are new or changed since a process last found them whole).

Usage::

    python benchmarks/startup_benchmark.py [--repeat 3] [--cold] [--no-peers]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTHON = Path(sys.executable)
STARTRACK = PYTHON.parent / "startrack"
REALDATA = ROOT.parent / "shared" / "realdata"
PHOTO = REALDATA / "smroid-cedar-solve" / "crappy.jpg"  # one that cedar-solve solves from the image too
BATCH_SOURCES = sorted((REALDATA / "smroid-cedar-solve").glob("*.jpg"))
BATCH_SIZE = 20
FOV_DEG = 10.2  # the cedar-solve photos' field, deg (truth.csv: 10.1-10.2)
SOLVE_ARGS = ("--fov-deg", str(FOV_DEG))

sys.path.insert(0, str(Path(__file__).resolve().parent / "peers"))

FIRST_SOLVE = r"""
import json, sys, time
t0 = time.perf_counter()
import startrack
from startrack.io import read_image
from startrack.cli._progress import ensure_database_for
from startrack.cli._batch_warmup import warm_up
t1 = time.perf_counter()
import startrack.solve, startrack.detect._detector, startrack.identify._quad_search, startrack.identify._refine
from numba.core.registry import CPUDispatcher
from startrack.identify import _match_kernel as match_kernel, _pose_kernel as pose_kernel, _quad_kernel as quad_kernel
loads = {}
for module in (quad_kernel, pose_kernel, match_kernel):
    for name, fn in vars(module).items():
        if isinstance(fn, CPUDispatcher):
            key = module.__name__.split(".")[-1].lstrip("_") + "." + name
            def timed(sig, ctx, _load=fn._cache.load_overload, _key=key):
                t = time.perf_counter()
                try:
                    return _load(sig, ctx)
                finally:
                    loads[_key] = loads.get(_key, 0.0) + time.perf_counter() - t
            fn._cache.load_overload = timed  # a timer around numba's own cache load
t2 = time.perf_counter()
image = read_image(sys.argv[1])
t2b = time.perf_counter()
ensure_database_for(float(sys.argv[2]))
t3 = time.perf_counter()
if sys.argv[3] == "warm":
    quad_kernel._bin(0)  # the smallest compiled function first: its load is numba's own start (see --help)
    warm_up(float(sys.argv[2]))
t4 = time.perf_counter()
first = startrack.solve_image(image, fov_deg=float(sys.argv[2]))
t5 = time.perf_counter()
second = startrack.solve_image(image, fov_deg=float(sys.argv[2]))
t6 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "solver_import_s": t2 - t1, "read_s": t2b - t2, "db_s": t3 - t2b,
                  "warm_up_s": t4 - t3, "first_s": t5 - t4,
                  "first_reported_s": first.solve_time_s, "second_s": t6 - t5, "solved": first.solved,
                  "loads": loads}))
"""

STACK_FLOOR = r"""
import json, time
t0 = time.perf_counter()
import numpy
t1 = time.perf_counter()
import scipy.spatial.transform
t2 = time.perf_counter()
import numba
t3 = time.perf_counter()

@numba.njit(cache=True)
def add(a, b):
    return a + b

add(1.0, 2.0)
t4 = time.perf_counter()
print(json.dumps({"numpy_s": t1 - t0, "scipy_spatial_s": t2 - t1, "numba_s": t3 - t2, "numba_first_s": t4 - t3}))
"""
"""The stack's floor: a file (numba caches only functions with a source file) run in a new process;
its first run compiles ``add`` into a temporary numba cache, the timed runs load it."""

CEDAR_SOLVE = r"""
import json, logging, sys, time
t0 = time.perf_counter()
logging.getLogger("tetra3.Tetra3").addHandler(logging.NullHandler())
import tetra3
from PIL import Image
t1 = time.perf_counter()
solver = tetra3.Tetra3("default_database")
t2 = time.perf_counter()
times, solved = [], 0
for path in sys.argv[2:]:
    t = time.perf_counter()
    with Image.open(path) as img:
        result = solver.solve_from_image(img, fov_estimate=float(sys.argv[1]), fov_max_error=0.5)
    times.append(time.perf_counter() - t)
    solved += result.get("RA") is not None
print(json.dumps({"import_s": t1 - t0, "load_db_s": t2 - t1, "solve_s": times, "solved": solved}))
"""


def _wall(cmd: list[str], env: dict | None = None) -> tuple[float, subprocess.CompletedProcess]:
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900)
    return time.perf_counter() - t0, done


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _median_wall(cmd: list[str], repeat: int, env: dict | None = None) -> tuple[float, float, float]:
    """(median, min) wall time and median CPU time (user + system) of ``cmd`` over ``repeat`` runs, s."""
    runs, cpu = [], []
    for _ in range(repeat):
        before = _children_cpu_s()
        elapsed, done = _wall(cmd, env=env)
        cpu.append(_children_cpu_s() - before)
        if done.returncode not in (0, 1):
            raise RuntimeError(f"{' '.join(cmd)} failed: {done.stderr.strip()[-500:]}")
        runs.append(elapsed)
    return statistics.median(runs), min(runs), statistics.median(cpu)


def _import_s(module: str, repeat: int) -> list[float]:
    code = f"import time; t = time.perf_counter(); import {module}; print(time.perf_counter() - t)"
    return [float(subprocess.run([str(PYTHON), "-c", code], capture_output=True, text=True, check=True).stdout)
            for _ in range(repeat)]


def measure_imports(repeat: int) -> None:
    print("\nimport time in a new process (s)")
    for module in ("startrack", "startrack.cli._solve_cmd", "startrack.cli._detect_cmd"):
        runs = _import_s(module, repeat)
        print(f"  {module:<26} median {statistics.median(runs):6.3f}  min {min(runs):6.3f}")


def _first_solve(mode: str) -> dict:
    done = subprocess.run([str(PYTHON), "-c", FIRST_SOLVE, str(PHOTO), str(FOV_DEG), mode],
                          capture_output=True, text=True, check=True, timeout=900)
    return json.loads(done.stdout.strip().splitlines()[-1])


def measure_first_solve(repeat: int) -> None:
    print(f"\nfirst solve in a new process, caches present ({PHOTO.name}, --fov-deg {FOV_DEG}; median of {repeat})")
    by_mode: dict[str, list[dict]] = {}
    for mode, label in (("warm", "with the warm-up (the commands)"), ("cold", "no warm-up (the library)")):
        runs = [_first_solve(mode) for _ in range(repeat)]
        by_mode[mode] = runs
        med = {k: statistics.median(r[k] for r in runs) for k in
               ("import_s", "solver_import_s", "read_s", "db_s", "warm_up_s", "first_s", "first_reported_s",
                "second_s")}
        print(f"  {label}:\n    import startrack + io {med['import_s']:.3f} s, solver modules (scipy.spatial, numba, "
              f"detect) {med['solver_import_s']:.3f} s, read {med['read_s']:.3f} s, database {med['db_s']:.3f} s,\n"
              f"    warm-up {med['warm_up_s']:.3f} s, first solve_image {med['first_s']:.3f} s "
              f"(solve_time_s {1e3 * med['first_reported_s']:.1f} ms), second {1e3 * med['second_s']:.1f} ms")
    loads = runs[-1]["loads"]
    total = sum(loads.values())
    print(f"  compiled functions loaded from numba's cache: {len(loads)}, {1e3 * total:.0f} ms in all "
          "(the last run, no warm-up; a function called only inside another is loaded with it; the first "
          "one loaded also pays for numba's start: its typing and lowering registries, numba.np.npyimpl and "
          "the rest, whatever the function)")
    first = by_mode["warm"][-1]["loads"]
    start = first.get("quad_kernel._bin", float("nan"))
    print(f"  with the warm-up, the smallest function (quad_kernel._bin) loaded first: {1e3 * start:.0f} ms, "
          f"numba's start; quad_kernel.search after it: {1e3 * first.get('quad_kernel.search', float('nan')):.0f} ms")
    order = {name: k for k, name in enumerate(loads)}
    for name, seconds in sorted(loads.items(), key=lambda kv: -kv[1]):
        print(f"    {name:<34} {1e3 * seconds:7.1f} ms   (loaded {order[name] + 1}.)")


def measure_floor(repeat: int) -> None:
    """What a new process of this stack costs before any startrack code (:data:`STACK_FLOOR`)."""
    print("\nthe floor of the stack, a new process with nothing of startrack (s; median of "
          f"{repeat}): numpy, scipy.spatial, numba, one cached compiled function")
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "floor.py"
        script.write_text(STACK_FLOOR)
        env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(tmp) / "numba")}
        _wall([str(PYTHON), str(script)], env=env)  # compiles add() into the cache
        bare, _, _ = _median_wall([str(PYTHON), "-c", "pass"], repeat)
        runs = [_wall([str(PYTHON), str(script)], env=env) for _ in range(repeat)]
    walls, parts = [t for t, _ in runs], [json.loads(done.stdout) for _, done in runs]
    med = {k: statistics.median(p[k] for p in parts) for k in parts[0]}
    print(f"  whole process        median {statistics.median(walls):6.3f}  min {min(walls):6.3f}   "
          f"(python -c pass: {bare:.3f})\n"
          f"  numpy {med['numpy_s']:.3f}, scipy.spatial {med['scipy_spatial_s']:.3f}, numba {med['numba_s']:.3f}, "
          f"numba's first cached function {med['numba_first_s']:.3f}")


def measure_cli(repeat: int, source_env: dict | None) -> None:
    print("\nstartrack solve IMAGE, wall time of the command (s; CPU = user + system time of the process)")
    solve = [str(STARTRACK), "solve", str(PHOTO), *SOLVE_ARGS]
    med, low, cpu = _median_wall(solve, repeat)
    print(f"  one image            median {med:6.3f}  min {low:6.3f}  CPU {cpu:6.3f}")
    if source_env is not None:
        med, low, cpu = _median_wall(solve, repeat, env=source_env)
        print(f"  one image, startrack compiled from source in each process (PYTHONDONTWRITEBYTECODE, as this "
              f"environment set it)\n                       median {med:6.3f}  min {low:6.3f}  CPU {cpu:6.3f}")
    med, low, cpu = _median_wall([str(STARTRACK), "detect", str(PHOTO)], repeat)
    print(f"  detect, one image    median {med:6.3f}  min {low:6.3f}  CPU {cpu:6.3f}")


def _batch_folder(root: Path) -> list[Path]:
    """20 links to the real photos (cycled), named in order."""
    paths = []
    for i in range(BATCH_SIZE):
        source = BATCH_SOURCES[i % len(BATCH_SOURCES)]
        link = root / f"{i:02d}_{source.name}"
        link.symlink_to(source)
        paths.append(link)
    return paths


def measure_batch(root: Path) -> list[Path]:
    paths = _batch_folder(root)
    print(f"\na batch of {BATCH_SIZE} photos ({len(BATCH_SOURCES)} different, 507-512 px JPEG), wall time")
    for jobs in (1, 2):
        elapsed, done = _wall([str(STARTRACK), "solve", str(root), *SOLVE_ARGS, "--jobs", str(jobs)])
        solved = sum(" solved " in line for line in done.stdout.splitlines())
        print(f"  startrack solve FOLDER --jobs {jobs}   {elapsed:6.2f} s total, "
              f"{elapsed / BATCH_SIZE:6.3f} s per image ({solved}/{BATCH_SIZE} solved)")
    t0, solved = time.perf_counter(), 0
    for path in paths:
        solved += _wall([str(STARTRACK), "solve", str(path), *SOLVE_ARGS])[1].returncode == 0
    elapsed = time.perf_counter() - t0
    print(f"  {BATCH_SIZE} x startrack solve IMAGE    {elapsed:6.2f} s total, {elapsed / BATCH_SIZE:6.3f} s per image "
          f"({solved}/{BATCH_SIZE} solved)")
    return paths


def measure_cedar(paths: list[Path], repeat: int) -> None:
    from cedar_env import CEDAR_VENV

    python = CEDAR_VENV / "bin" / "python"
    if not python.is_file():
        print(f"\ncedar-solve: left out, its environment {CEDAR_VENV} is absent "
              "(python benchmarks/peers/cedar_env.py creates it)")
        return
    print("\ncedar-solve 0.5.1 (tetra3), the command-line equivalent: a new process that imports tetra3, "
          "loads its database and solves (solve_from_image, fov_estimate 10.2 deg)")
    one = []
    for _ in range(repeat):
        elapsed, done = _wall([str(python), "-c", CEDAR_SOLVE, str(FOV_DEG), str(PHOTO)])
        one.append((elapsed, json.loads(done.stdout.strip().splitlines()[-1])))
    med = statistics.median(e for e, _ in one)
    inner = one[-1][1]
    print(f"  one image            median {med:6.3f} s wall (import {inner['import_s']:.3f} s, database "
          f"{inner['load_db_s']:.3f} s, solve {1e3 * inner['solve_s'][0]:.0f} ms; solved {inner['solved']})")
    elapsed, done = _wall([str(python), "-c", CEDAR_SOLVE, str(FOV_DEG), *map(str, paths)])
    inner = json.loads(done.stdout.strip().splitlines()[-1])
    print(f"  {BATCH_SIZE} images, one process {elapsed:6.2f} s total, {elapsed / BATCH_SIZE:6.3f} s per image "
          f"({inner['solved']}/{BATCH_SIZE} solved; median solve {1e3 * statistics.median(inner['solve_s']):.0f} ms)")


def measure_astrometry(work: Path, paths: list[Path], repeat: int) -> None:
    """Debian's ``solve-field`` on the same photo (median of ``repeat`` new processes) and on the
    batch's ``paths`` in one command (it takes several files), FOV within 10 % of :data:`FOV_DEG`;
    solved = the ``.solved`` file it writes for each."""
    from astrometry_env import ensure_solve_field, index_files

    exe, why = ensure_solve_field()
    if exe is None:
        print(f"\nastrometry.net: left out, {why}")
        return
    cmd = [exe, "--overwrite", "--no-plots", "--no-verify", "--dir", str(work), "--scale-units", "degwidth",
           "--scale-low", str(FOV_DEG * 0.9), "--scale-high", str(FOV_DEG * 1.1), "--cpulimit", "60"]
    med, low, _ = _median_wall([*cmd, str(PHOTO)], repeat)
    solved = (work / f"{PHOTO.stem}.solved").exists()
    print(f"\nastrometry.net {_astrometry_version(exe)} solve-field, {len(index_files())} index files "
          f"({', '.join(sorted({p.parent.as_posix() for p in index_files()}))})")
    print(f"  one image            median {med:6.3f} s wall, min {low:6.3f} s (solved {solved})")
    elapsed, _ = _wall([*cmd, *map(str, paths)])
    solved_n = sum((work / f"{path.stem}.solved").exists() for path in paths)
    print(f"  {BATCH_SIZE} images, one command {elapsed:6.2f} s total, {elapsed / BATCH_SIZE:6.3f} s per image "
          f"({solved_n}/{BATCH_SIZE} solved)")


def _astrometry_version(exe: str) -> str:
    return subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.strip()


def measure_cold_compile(numba_dir: Path) -> None:
    """``startrack warm-up`` into the empty ``numba_dir``, then once more from it."""
    print(f"\nthe one-time compile: startrack warm-up with an empty numba cache (NUMBA_CACHE_DIR={numba_dir})")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(numba_dir)}
    elapsed, done = _wall([str(STARTRACK), "warm-up"], env=env)
    print(f"  compile run   {elapsed:6.2f} s wall; it said: {' | '.join(done.stderr.strip().splitlines())}")
    elapsed, done = _wall([str(STARTRACK), "warm-up"], env=env)
    said = " | ".join(done.stderr.strip().splitlines()) or "nothing: loaded from the cache"
    print(f"  the next run  {elapsed:6.2f} s wall; it said: {said}")


def describe_numba_cache() -> None:
    from startrack.cache import cache_dir
    from startrack.numba_cache import numba_cache_dir

    folder = Path(os.environ.get("NUMBA_CACHE_DIR") or numba_cache_dir(cache_dir()))
    files = [p for p in folder.rglob("*") if p.is_file()] if folder.is_dir() else []
    print(f"numba cache {folder}: {len(files)} files, {sum(p.stat().st_size for p in files) / 1e6:.1f} MB")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=3, help="fresh processes per timing (median printed)")
    parser.add_argument("--cold", action="store_true", help="also time the one-time compile (about 15-25 s)")
    parser.add_argument("--no-peers", action="store_true", help="leave out cedar-solve and astrometry.net")
    args = parser.parse_args(argv)
    if not PHOTO.is_file():
        print(f"the real photos are absent ({REALDATA}); nothing measured")
        return 1
    print(f"startup benchmark: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the start")
    with tempfile.TemporaryDirectory() as numba_dir, tempfile.TemporaryDirectory() as pycache:
        source_env = _with_bytecode(Path(pycache))
        if args.cold:
            measure_cold_compile(Path(numba_dir))
            os.environ["NUMBA_CACHE_DIR"] = numba_dir  # every later process: the fresh cache
        measure_warm(args, source_env)
    print(f"\nload average {os.getloadavg()[0]:.2f} at the end (2 shared cores: figures vary with it)")
    return 0


def _with_bytecode(pycache: Path) -> dict | None:
    """Let the measured processes keep startrack's bytecode, as an installed package has it.

    With ``PYTHONDONTWRITEBYTECODE`` set (as in this project's development environment) every
    process of an editable checkout compiles startrack's ~80 modules from source, which no user of
    an install pays. The benchmark's processes then write and reuse bytecode under ``pycache``
    (``PYTHONPYCACHEPREFIX``; nothing is written into the checkout). Returns the environment as it
    was (for the one measurement that shows the difference), or None when bytecode was not off.
    """
    if not os.environ.get("PYTHONDONTWRITEBYTECODE"):
        return None
    as_set = dict(os.environ)
    del os.environ["PYTHONDONTWRITEBYTECODE"]
    os.environ["PYTHONPYCACHEPREFIX"] = str(pycache)
    print(f"PYTHONDONTWRITEBYTECODE was set: the measured processes keep bytecode under {pycache} "
          "(PYTHONPYCACHEPREFIX), as an installed package does")
    return as_set


def measure_warm(args: argparse.Namespace, source_env: dict | None = None) -> None:
    """Everything but the compile, with the caches present."""
    _wall([str(STARTRACK), "warm-up"])  # caches present: default database built, kernels compiled
    _wall([str(STARTRACK), "solve", str(PHOTO), *SOLVE_ARGS])  # and the 10.2 deg database, its kernels' types
    describe_numba_cache()
    measure_imports(args.repeat)
    measure_first_solve(args.repeat)
    measure_floor(args.repeat)
    measure_cli(args.repeat, source_env)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "batch"
        folder.mkdir()
        paths = measure_batch(folder)
        if not args.no_peers:
            measure_cedar(paths, args.repeat)
            measure_astrometry(Path(tmp) / "astrometry", paths, args.repeat)


if __name__ == "__main__":
    sys.exit(main())
