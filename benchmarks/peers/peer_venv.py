"""A benchmark peer's own virtual environment (DESIGN.md §4: peers whose pins clash with ours,
or that we only compare with, never go into startrack's environment).

:class:`PeerEnv` creates ``benchmarks/.venv-<name>`` once with the interpreter running the
benchmark, runs its ``pip install`` steps in order, and writes a stamp file recording what was
asked for and how long it took; the environment is re-created when the request changes.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
import venv
from dataclasses import dataclass
from pathlib import Path

PEERS_DIR = Path(__file__).resolve().parent
BENCH_DIR = PEERS_DIR.parent


@dataclass(frozen=True)
class PeerEnv:
    """A peer environment.

    Attributes
    ----------
    label : str
        For messages ("cedar-solve", "SEP / photutils", ...).
    env_dir : Path
    installs : tuple of tuple of str
        ``pip install`` argument lists, run in order.
    versions_code : str
        Optional Python run in the environment after installing; its printed words are stored
        under ``versions`` in the stamp.
    """

    label: str
    env_dir: Path
    installs: tuple[tuple[str, ...], ...]
    versions_code: str = ""

    @property
    def python(self) -> Path:
        return self.env_dir / ("Scripts" if os.name == "nt" else "bin") / "python"

    @property
    def stamp_path(self) -> Path:
        return self.env_dir / ".peer-installed.json"

    def wanted(self) -> dict:
        return {"installs": [list(step) for step in self.installs], "base_python": sys.version.split()[0]}

    def read_stamp(self) -> dict | None:
        """What the environment was created with, or None if it is not ready."""
        if not (self.stamp_path.exists() and self.python.exists()):
            return None
        try:
            return json.loads(self.stamp_path.read_text())
        except (OSError, json.JSONDecodeError):
            return None

    def ensure(self, *, force: bool = False) -> Path:
        """Create the environment unless it is current; return its Python interpreter."""
        stamp = self.read_stamp()
        if not force and stamp is not None and all(stamp.get(k) == v for k, v in self.wanted().items()):
            return self.python
        if self.env_dir.exists():
            shutil.rmtree(self.env_dir)
        t0 = time.perf_counter()
        print(f"creating the {self.label} environment in {self.env_dir}", file=sys.stderr, flush=True)
        venv.EnvBuilder(with_pip=True).create(self.env_dir)
        for step in self.installs:
            cmd = [str(self.python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", *step]
            print("+", " ".join(cmd), file=sys.stderr, flush=True)
            subprocess.run(cmd, check=True)
        stamp = {**self.wanted(), "created_s": time.perf_counter() - t0}
        if self.versions_code:
            stamp["versions"] = subprocess.run([str(self.python), "-c", self.versions_code], check=True,
                                               capture_output=True, text=True).stdout.split()
        self.stamp_path.write_text(json.dumps(stamp, indent=1))
        print(f"{self.label} environment ready in {stamp['created_s']:.1f} s", file=sys.stderr, flush=True)
        return self.python

    def main(self, argv: list[str] | None = None) -> int:
        """Command line: create (``--force``: re-create) the environment and say what it holds."""
        import argparse

        parser = argparse.ArgumentParser(description=f"create the {self.label} benchmark environment")
        parser.add_argument("--force", action="store_true", help="re-create the environment")
        args = parser.parse_args(argv)
        python = self.ensure(force=args.force)
        stamp = self.read_stamp() or {}
        print(f"python: {python}")
        print(f"installs: {stamp.get('installs')}; versions: {stamp.get('versions')}; "
              f"created in {stamp.get('created_s', float('nan')):.1f} s")
        return 0
