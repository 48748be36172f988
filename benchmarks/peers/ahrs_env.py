"""The ahrs peer (PyPI ``ahrs``): its own virtual environment, never a project dependency.

``ahrs`` (attitude and heading reference systems) has QUEST, Davenport's q-method and TRIAD for
two vector pairs (accelerometer and magnetometer). It installs with numpy 2, but it is a peer to
compare with, not something startrack uses, so it lives in ``benchmarks/.venv-ahrs`` (git-ignored),
created by :func:`ensure_ahrs_env` with the interpreter running the benchmark; ``ahrs_runner.py``
runs inside it. A stamp file records the version and how long the set-up took.

Run as a script to create the environment::

    python benchmarks/peers/ahrs_env.py [--force]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
import venv
from pathlib import Path

import numpy as np

PEERS_DIR = Path(__file__).resolve().parent
AHRS_VENV = PEERS_DIR.parent / ".venv-ahrs"
RUNNER = PEERS_DIR / "ahrs_runner.py"
AHRS_VERSION = "0.4.0"
REQUIREMENTS = (f"ahrs=={AHRS_VERSION}", "numpy")
STAMP_NAME = ".ahrs-installed.json"


def _python(env_dir: Path) -> Path:
    return env_dir / ("Scripts" if os.name == "nt" else "bin") / "python"


def _wanted() -> dict:
    return {"ahrs": AHRS_VERSION, "requirements": list(REQUIREMENTS), "base_python": sys.version.split()[0]}


def read_stamp(env_dir: Path = AHRS_VENV) -> dict | None:
    """What the environment was created with, or None if it is not ready."""
    path = env_dir / STAMP_NAME
    if not (path.exists() and _python(env_dir).exists()):
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None


def ensure_ahrs_env(env_dir: Path = AHRS_VENV, *, force: bool = False) -> Path:
    """Create the ahrs environment unless it is current; return its Python interpreter."""
    stamp = read_stamp(env_dir)
    if not force and stamp is not None and all(stamp.get(k) == v for k, v in _wanted().items()):
        return _python(env_dir)
    if env_dir.exists():
        shutil.rmtree(env_dir)
    t0 = time.perf_counter()
    print(f"creating the ahrs environment in {env_dir}", file=sys.stderr, flush=True)
    venv.EnvBuilder(with_pip=True).create(env_dir)
    python = _python(env_dir)
    cmd = [str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", *REQUIREMENTS]
    subprocess.run(cmd, check=True)
    created_s = time.perf_counter() - t0
    (env_dir / STAMP_NAME).write_text(json.dumps({**_wanted(), "created_s": created_s}, indent=1))
    return python


def run_ahrs(problems_npz: Path, out_npz: Path, *, python: Path | None = None) -> dict[str, np.ndarray]:
    """Solve the two-vector problems of ``problems_npz`` with ahrs; return quaternions and times.

    The runner writes, per method (``quest``, ``davenport``, ``triad``), ``<method>_quat``
    (M, 4), scipy order and convention (rotation mapping reference onto observed), and
    ``<method>_time_s`` (total wall time of the one-by-one loop).
    """
    python = ensure_ahrs_env() if python is None else python
    subprocess.run([str(python), str(RUNNER), str(problems_npz), str(out_npz)], check=True)
    with np.load(out_npz, allow_pickle=False) as npz:
        return {name: npz[name] for name in npz.files}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="re-create the environment")
    args = parser.parse_args(argv)
    print(ensure_ahrs_env(force=args.force))
    return 0


if __name__ == "__main__":
    sys.exit(main())
