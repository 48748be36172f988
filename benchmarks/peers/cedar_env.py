"""The cedar-solve peer: its own virtual environment, and running it on a file of star lists.

cedar-solve (PyPI ``cedar-solve``, a fork of ESA's tetra3 that ships its pattern database) pins
``numpy<2``, so it cannot share startrack's environment. :func:`ensure_cedar_env` creates
``benchmarks/.venv-cedar`` once (with the interpreter running this script) and installs it there;
:func:`run_cedar` runs ``cedar_runner.py`` inside it on an ``.npz`` of star lists written by
:func:`starlists.save_for_peer` and reads the results back.

cedar-solve 0.5.1 also pins ``Pillow<9``, which has no wheel for Python 3.11 or newer. Pillow is
used by tetra3 only to read images and draw its optional "visual" output, never by
``solve_from_centroids``, so cedar-solve is installed with ``--no-deps`` and its other
requirements (``numpy<2``, ``scipy<2``) plus a current Pillow wheel are installed beside it.

Run as a script to create the environment and print how long it took::

    python benchmarks/peers/cedar_env.py [--force]
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
CEDAR_VENV = BENCH_DIR / ".venv-cedar"
RUNNER = PEERS_DIR / "cedar_runner.py"
CEDAR_VERSION = "0.5.1"
REQUIREMENTS = ("numpy>=1.21.1,<2", "scipy>=1.7.1,<2", "pillow")
STAMP_NAME = ".cedar-installed.json"


def _python(env_dir: Path) -> Path:
    return env_dir / ("Scripts" if os.name == "nt" else "bin") / "python"


def _wanted() -> dict:
    return {"cedar_solve": CEDAR_VERSION, "requirements": list(REQUIREMENTS),
            "base_python": sys.version.split()[0]}


def _pip(python: Path, *args: str) -> None:
    cmd = [str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", *args]
    print("+", " ".join(cmd), file=sys.stderr, flush=True)
    subprocess.run(cmd, check=True)


def read_stamp(env_dir: Path = CEDAR_VENV) -> dict | None:
    """What the environment was created with (and how long it took), or None if not ready."""
    path = env_dir / STAMP_NAME
    if not (path.exists() and _python(env_dir).exists()):
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, json.JSONDecodeError):
        return None


def ensure_cedar_env(env_dir: Path = CEDAR_VENV, *, force: bool = False) -> Path:
    """Create the cedar-solve virtual environment unless it is already current.

    Returns the path of its Python interpreter. The stamp file ``.cedar-installed.json`` in the
    environment records the versions asked for and ``created_s``, the wall-clock time that
    creating the environment and installing took.
    """
    stamp = read_stamp(env_dir)
    wanted = _wanted()
    if not force and stamp is not None and all(stamp.get(k) == v for k, v in wanted.items()):
        return _python(env_dir)
    if env_dir.exists():
        shutil.rmtree(env_dir)
    t0 = time.perf_counter()
    print(f"creating the cedar-solve environment in {env_dir}", file=sys.stderr, flush=True)
    venv.EnvBuilder(with_pip=True).create(env_dir)
    python = _python(env_dir)
    _pip(python, *REQUIREMENTS)
    _pip(python, "--no-deps", f"cedar-solve=={CEDAR_VERSION}")
    created_s = time.perf_counter() - t0
    (env_dir / STAMP_NAME).write_text(json.dumps({**wanted, "created_s": created_s}, indent=1))
    print(f"cedar-solve environment ready in {created_s:.1f} s", file=sys.stderr, flush=True)
    return python


def run_cedar(lists_npz: Path, out_npz: Path, *, solve_timeout_ms: float = 5000.0,
              progress: int = 0, python: Path | None = None) -> dict[str, np.ndarray]:
    """Solve every star list in ``lists_npz`` with cedar-solve; return its per-list results.

    The runner writes ``out_npz`` (arrays ``solved``, ``ra_deg``, ``dec_deg``, ``roll_deg``,
    ``fov_deg``, ``prob``, ``time_s``, ``status``) and a JSON header with the database's
    properties, returned under the key ``"database"`` (a dict).
    """
    python = ensure_cedar_env() if python is None else python
    cmd = [str(python), str(RUNNER), str(lists_npz), str(out_npz),
           "--solve-timeout-ms", str(solve_timeout_ms), "--progress", str(progress)]
    subprocess.run(cmd, check=True)
    with np.load(out_npz, allow_pickle=False) as npz:
        results = {name: npz[name] for name in npz.files}
    results["database"] = json.loads(str(results.pop("database_json")))
    return results


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="re-create the environment")
    args = parser.parse_args(argv)
    python = ensure_cedar_env(force=args.force)
    stamp = read_stamp() or {}
    print(f"python: {python}")
    print(f"cedar-solve {stamp.get('cedar_solve')}; environment created in "
          f"{stamp.get('created_s', float('nan')):.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
