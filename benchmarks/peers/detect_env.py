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

import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # as a script, or imported as peers.*
from peer_venv import BENCH_DIR, PEERS_DIR, PeerEnv  # noqa: E402

PEERS_VENV = BENCH_DIR / ".venv-detectpeers"
RUNNER = PEERS_DIR / "detect_runner.py"
REQUIREMENTS = ("sep==1.4.1", "photutils==3.0.0", "numpy>=2")
DETECT_PEERS = PeerEnv("SEP / photutils", PEERS_VENV, (REQUIREMENTS,),
                       versions_code="import sep, photutils, numpy; "
                                     "print(sep.__version__, photutils.__version__, numpy.__version__)")


def ensure_detect_env(*, force: bool = False) -> Path:
    """Create the SEP + photutils environment unless it is current; return its interpreter."""
    return DETECT_PEERS.ensure(force=force)


def run_peers(frames_npz: Path, out_npz: Path, *, repeats: int = 5, clock: str = "wall",
              python: Path | None = None) -> dict[str, np.ndarray]:
    """Run SEP and DAOStarFinder on every frame of ``frames_npz`` (see ``detect_runner.py``).

    Returns the runner's arrays: per method ``<method>_x``, ``<method>_y``, ``<method>_flux``,
    ``<method>_frame`` (frame index of each detection) and ``<method>_time_s`` (median time per
    frame over ``repeats`` runs, by the wall clock or with ``clock="cpu"`` the process's CPU time).
    """
    python = ensure_detect_env() if python is None else python
    cmd = [str(python), str(RUNNER), str(frames_npz), str(out_npz), "--repeats", str(repeats),
           "--clock", clock]
    subprocess.run(cmd, check=True)
    with np.load(out_npz, allow_pickle=False) as npz:
        return {name: npz[name] for name in npz.files}


if __name__ == "__main__":
    sys.exit(DETECT_PEERS.main())
