#!/usr/bin/env python3
"""Set up the project and run its main jobs, with nothing but Python 3.11+ and pip.

Usage::

    python3 tasks.py demo     # create .venv, install startrack, simulate and solve a star image
    python3 tasks.py test     # create .venv, install startrack with test tools, run ruff, mypy, pytest
    python3 tasks.py bench    # run the benchmarks in benchmarks/ (installs their peers)

The virtual environment lives in ``.venv`` next to this file; it is created on first use and
reused afterwards (re-installed when ``pyproject.toml`` changes).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PY = BIN / "python"
STAMP = VENV / ".startrack-installed"


def _run(*cmd: str | Path) -> None:
    print("+", " ".join(str(c) for c in cmd), flush=True)
    subprocess.run([str(c) for c in cmd], check=True, cwd=ROOT)


def ensure_env(extra: str = "test") -> None:
    """Create ``.venv`` and install the package (editable) unless it is already current."""
    if sys.version_info < (3, 11):
        sys.exit(f"startrack needs Python 3.11 or newer; this is {sys.version.split()[0]}")
    if not PY.exists():
        print(f"creating virtual environment in {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    digest = hashlib.sha256((ROOT / "pyproject.toml").read_bytes() + extra.encode()).hexdigest()
    if STAMP.exists() and STAMP.read_text() == digest:
        return
    _run(PY, "-m", "pip", "install", "--quiet", "--upgrade", "pip")
    _run(PY, "-m", "pip", "install", "--quiet", "-e", f".[{extra}]")
    STAMP.write_text(digest)


CHROMIUM = Path("/usr/bin/chromium")


def ensure_browser() -> None:
    """Install Debian's ``chromium`` for the browser tests when it is missing and we may.

    The tests drive it through Playwright with ``executable_path`` (Playwright's own browser
    download cannot work offline); without it, and without root and ``apt-get`` to install it,
    the browser tests are skipped with that reason.
    """
    if CHROMIUM.exists():
        return
    apt = shutil.which("apt-get")
    if apt is None or not hasattr(os, "geteuid") or os.geteuid() != 0:
        print(f"note: {CHROMIUM} is missing and cannot be installed here (needs root and apt-get); "
              "the browser tests will be skipped", flush=True)
        return
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    print("installing Debian's chromium for the browser tests", flush=True)
    subprocess.run([apt, "-q", "update"], check=False, env=env, stdout=subprocess.DEVNULL)
    subprocess.run([apt, "install", "-y", "-q", "--no-install-recommends", "chromium"], check=True, env=env,
                   stdout=subprocess.DEVNULL)


TEST_CACHE = ROOT / ".test-cache"
"""The tests' cache folder (``tests/conftest.py`` points ``STARTRACK_CACHE_DIR`` at it)."""


def warm_test_cache() -> None:
    """Build the default pattern database and compile the kernels in the tests' cache, once,
    before the tests start (``startrack warm-up``; 71-88 s on a fresh checkout of the 2-core
    reference machine, about 1 s afterwards).

    Without it the test processes all do this work at once on a fresh checkout: the web tests'
    server then waited more than its start-up limit for its worker to warm up.
    """
    print(f"warming the tests' cache in {TEST_CACHE} (once after a checkout or an upgrade)", flush=True)
    env = {**os.environ, "STARTRACK_CACHE_DIR": str(TEST_CACHE)}
    subprocess.run([str(PY), "-m", "startrack", "warm-up"], check=True, cwd=ROOT, env=env)


def _parallel(rest: list[str]) -> list[str]:
    """pytest-xdist's workers: one per usable CPU, at most four, unless the caller gave ``-n``;
    each test file whole in one worker, in its order (``--dist loadfile``: some tests build on the
    jobs an earlier test of their file left on the session's server).

    The suite waits on sub-processes, Dask clusters and a browser as much as it computes: two
    workers on the 2-core reference machine took it from 470-560 s to 227-277 s of wall time.
    """
    if any(arg.startswith(("-n", "--numprocesses")) for arg in rest):
        return []
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return ["-n", str(min(cpus, 4)), "--dist", "loadfile"]


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in {"demo", "test", "bench"}:
        print(__doc__)
        return 2
    task, rest = argv[0], argv[1:]
    ensure_env()
    try:
        if task == "demo":
            _run(BIN / "startrack", "demo", *rest)
        elif task == "test":
            ensure_browser()
            _run(PY, "-m", "ruff", "check", "src", "tests", "benchmarks")
            _run(PY, "-m", "mypy")  # files and settings: [tool.mypy] in pyproject.toml
            warm_test_cache()
            _run(PY, "-m", "pytest", *_parallel(rest), *rest)
        else:
            _run(PY, "benchmarks/run_all.py", *rest)
    except subprocess.CalledProcessError as exc:
        return exc.returncode or 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
