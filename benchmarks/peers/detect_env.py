"""The detection peers, SEP and photutils, in their own virtual environment.

SEP (PyPI ``sep``, the C core of Source Extractor as a library) and photutils (its
``DAOStarFinder``) are benchmark peers only, never dependencies of startrack, so they live in
``benchmarks/.venv-detectpeers`` (git-ignored). :func:`ensure_detect_env` creates it once, with
the interpreter running the benchmark; :func:`run_peers` runs ``detect_runner.py`` inside it on an
``.npz`` of frames and reads the results back.

Run as a script to create the environment::

    python benchmarks/peers/detect_env.py [--force]
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
BENCH_DIR = PEERS_DIR.parent
PEERS_VENV = BENCH_DIR / ".venv-detectpeers"
RUNNER = PEERS_DIR / "detect_runner.py"
REQUIREMENTS = ("sep==1.4.1", "photutils==3.0.0", "numpy>=2")
STAMP_NAME = ".detectpeers-installed.json"


def _python(env_dir: Path) -> Path:
    return env_dir / ("Scripts" if os.name == "nt" else "bin") / "python"


def _wanted() -> dict:
    return {"requirements": list(REQUIREMENTS), "base_python": sys.version.split()[0]}


def read_stamp(env_dir: Path = PEERS_VENV) -> dict | None:
    """What the environment was created with, or None if it is not ready."""
    path = env_dir / STAMP_NAME
    if not (path.exists() and _python(env_dir).exists()):
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None


def ensure_detect_env(env_dir: Path = PEERS_VENV, *, force: bool = False) -> Path:
    """Create the SEP + photutils environment unless it is current; returns its interpreter."""
    stamp = read_stamp(env_dir)
    wanted = _wanted()
    if not force and stamp is not None and all(stamp.get(k) == v for k, v in wanted.items()):
        return _python(env_dir)
    if env_dir.exists():
        shutil.rmtree(env_dir)
    t0 = time.perf_counter()
    print(f"creating the SEP / photutils environment in {env_dir}", file=sys.stderr, flush=True)
    venv.EnvBuilder(with_pip=True).create(env_dir)
    python = _python(env_dir)
    cmd = [str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check",
           *REQUIREMENTS]
    print("+", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True)
    created_s = time.perf_counter() - t0
    versions = subprocess.run(
        [str(python), "-c", "import sep, photutils, numpy; "
         "print(sep.__version__, photutils.__version__, numpy.__version__)"],
        check=True, capture_output=True, text=True).stdout.split()
    stamp = {**wanted, "created_s": created_s, "versions": dict(zip(
        ("sep", "photutils", "numpy"), versions, strict=True))}
    (env_dir / STAMP_NAME).write_text(json.dumps(stamp, indent=1))
    print(f"peer environment ready in {created_s:.1f} s", file=sys.stderr, flush=True)
    return python


def run_peers(frames_npz: Path, out_npz: Path, *, repeats: int = 5,
              python: Path | None = None) -> dict[str, np.ndarray]:
    """Run SEP and DAOStarFinder on every frame of ``frames_npz`` (see ``detect_runner.py``).

    Returns the runner's arrays: per method ``<method>_x``, ``<method>_y``, ``<method>_flux``,
    ``<method>_frame`` (frame index of each detection) and ``<method>_time_s`` (median time per
    frame over ``repeats`` runs).
    """
    python = ensure_detect_env() if python is None else python
    cmd = [str(python), str(RUNNER), str(frames_npz), str(out_npz), "--repeats", str(repeats)]
    subprocess.run(cmd, check=True)
    with np.load(out_npz, allow_pickle=False) as npz:
        return {name: npz[name] for name in npz.files}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="re-create the environment")
    args = parser.parse_args(argv)
    python = ensure_detect_env(force=args.force)
    stamp = read_stamp() or {}
    print(f"python: {python}")
    print(f"versions: {stamp.get('versions')}; created in {stamp.get('created_s', 0):.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
