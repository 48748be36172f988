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

import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # as a script, or imported as peers.*
from peer_venv import BENCH_DIR, PEERS_DIR, PeerEnv  # noqa: E402

AHRS_VENV = BENCH_DIR / ".venv-ahrs"
RUNNER = PEERS_DIR / "ahrs_runner.py"
AHRS_VERSION = "0.4.0"
AHRS = PeerEnv("ahrs", AHRS_VENV, ((f"ahrs=={AHRS_VERSION}", "numpy"),),
               versions_code="import ahrs, numpy; print(ahrs.__version__, numpy.__version__)")


def ensure_ahrs_env(*, force: bool = False) -> Path:
    """Create the ahrs environment unless it is current; return its Python interpreter."""
    return AHRS.ensure(force=force)


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


if __name__ == "__main__":
    sys.exit(AHRS.main())
