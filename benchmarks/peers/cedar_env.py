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

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # as a script, or imported as peers.*
from peer_venv import BENCH_DIR, PEERS_DIR, PeerEnv  # noqa: E402

CEDAR_VENV = BENCH_DIR / ".venv-cedar"
RUNNER = PEERS_DIR / "cedar_runner.py"
CEDAR_VERSION = "0.5.1"
REQUIREMENTS = ("numpy>=1.21.1,<2", "scipy>=1.7.1,<2", "pillow")
CEDAR = PeerEnv("cedar-solve", CEDAR_VENV, (REQUIREMENTS, ("--no-deps", f"cedar-solve=={CEDAR_VERSION}")),
                versions_code="import numpy, importlib.metadata as m; "
                              "print(m.version('cedar-solve'), numpy.__version__)")


def ensure_cedar_env(*, force: bool = False) -> Path:
    """Create the cedar-solve environment unless it is current; return its Python interpreter."""
    return CEDAR.ensure(force=force)


def run_cedar(lists_npz: Path, out_npz: Path, *, solve_timeout_ms: float = 5000.0,
              progress: int = 0, python: Path | None = None, clock: str = "wall") -> dict[str, np.ndarray]:
    """Solve every star list in ``lists_npz`` with cedar-solve; return its per-list results.

    The runner writes ``out_npz`` (arrays ``solved``, ``ra_deg``, ``dec_deg``, ``roll_deg``,
    ``fov_deg``, ``prob``, ``time_s``, ``status``) and a JSON header with the database's
    properties, returned under the key ``"database"`` (a dict). ``clock`` is the runner's
    ``--clock``: "wall" or "cpu" (the solving thread's CPU time).
    """
    python = ensure_cedar_env() if python is None else python
    cmd = [str(python), str(RUNNER), str(lists_npz), str(out_npz),
           "--solve-timeout-ms", str(solve_timeout_ms), "--progress", str(progress), "--clock", clock]
    subprocess.run(cmd, check=True)
    with np.load(out_npz, allow_pickle=False) as npz:
        results = {name: npz[name] for name in npz.files}
    results["database"] = json.loads(str(results.pop("database_json")))
    return results


if __name__ == "__main__":
    sys.exit(CEDAR.main())
