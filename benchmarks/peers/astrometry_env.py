"""The astrometry.net peer: Debian's ``solve-field`` and an index set that covers our photos.

astrometry.net is a C program with its own data, not a Python package, so it does not go into a
virtual environment: :func:`ensure_solve_field` finds ``solve-field`` and its index files, and
when either is missing installs Debian's ``astrometry.net`` and the Tycho-2 index files for
skymarks of 1-33 deg (:data:`PACKAGES`, about 45 MB installed) with ``apt-get``, which needs root.
Elsewhere it says what is missing and the benchmark leaves the peer out.

Run as a script to install it and print what was found::

    python benchmarks/peers/astrometry_env.py
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

PACKAGES = ("astrometry.net", "astrometry-data-tycho2-10-19-littleendian")
"""Debian's solver and the index files of skymarks 60-2000 arcmin (fields of about 1-33 deg)."""
INDEX_FOLDERS = (Path("/usr/share/astrometry"), Path("/usr/local/astrometry/data"))
"""Where Debian's and a source install's index files lie, before their configuration's ``add_path``."""
CONFIGS = (Path("/etc/astrometry.cfg"), Path("/usr/local/astrometry/etc/astrometry.cfg"))
"""astrometry.net's configuration files (Debian's, a source install's), whose ``add_path`` lines name more folders."""


def index_files() -> list[Path]:
    """The index files (``index-*.fits``) on the folders astrometry.net's configuration names."""
    folders = list(INDEX_FOLDERS)
    for cfg in CONFIGS:
        if cfg.is_file():
            folders += [Path(line.split(None, 1)[1].strip()) for line in cfg.read_text().splitlines()
                        if line.startswith("add_path") and len(line.split(None, 1)) == 2]
    return sorted({p for f in folders if f.is_dir() for p in f.glob("index-*.fits")})


def _missing() -> str | None:
    """What keeps ``solve-field`` from solving here, or None when nothing does."""
    exe = shutil.which("solve-field")
    if exe is None:
        return "solve-field is not installed"
    if not index_files():
        return (f"{exe} is installed but no index files (index-*.fits) are on its paths "
                "(/etc/astrometry.cfg add_path), so it cannot solve")
    return None


def _install() -> None:
    """``apt-get install`` :data:`PACKAGES` (root only), with a line saying so and its time."""
    apt = shutil.which("apt-get")
    if apt is None or not hasattr(os, "geteuid") or os.geteuid() != 0:
        return
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    print(f"installing Debian's {' and '.join(PACKAGES)} for the astrometry.net peer", flush=True)
    t0 = time.perf_counter()
    subprocess.run([apt, "-q", "update"], check=False, env=env, stdout=subprocess.DEVNULL)
    done = subprocess.run([apt, "install", "-y", "-q", "--no-install-recommends", *PACKAGES], check=False,
                          env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        print(f"apt-get install failed ({done.returncode}): {done.stderr.strip().splitlines()[-1:]}", flush=True)
        return
    print(f"astrometry.net installed in {time.perf_counter() - t0:.1f} s", flush=True)


def ensure_solve_field() -> tuple[str | None, str]:
    """``solve-field``'s path and "" when it can solve here, installing it first when it is
    missing and this process may (root and ``apt-get``); else None and why not."""
    if _missing() is not None:
        _install()
    why = _missing()
    if why is not None:
        return None, why + " (installing it needs root and apt-get: Debian's " + " and ".join(PACKAGES) + ")"
    return shutil.which("solve-field"), ""


if __name__ == "__main__":
    path, reason = ensure_solve_field()
    print(f"solve-field: {path}, {len(index_files())} index files" if path else f"astrometry.net: {reason}")
    sys.exit(0 if path else 1)
