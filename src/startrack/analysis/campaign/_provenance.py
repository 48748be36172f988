"""Where a campaign's numbers come from: package version, git commit, catalog and database hashes."""

from __future__ import annotations

import hashlib
import socket
import subprocess
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from ... import __version__
from ._spec import Cell


def git_commit() -> str | None:
    """The commit of the source tree startrack runs from, when it is a git checkout (else None)."""
    here = Path(__file__).resolve().parent
    try:
        done = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True,
                              timeout=5, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    commit = done.stdout.strip()
    return commit if done.returncode == 0 and len(commit) == 40 else None


def catalog_hash() -> str:
    """SHA-256 (first 16 hex digits) of the Hipparcos-2 columns the trials use."""
    from ...catalog import load_catalog

    cat = load_catalog()
    digest = hashlib.sha256()
    for column in (cat.hip, cat.ra_rad, cat.dec_rad, cat.pm_ra_mas_yr, cat.pm_dec_mas_yr, cat.v_mag):
        digest.update(np.ascontiguousarray(column).tobytes())
    return digest.hexdigest()[:16]


def _fov_range(params: dict[str, Any]) -> tuple[float, float] | None:
    from ...solve import FOV_DEG_TOLERANCE

    if "fov_known" not in params:
        return None
    if params["fov_known"]:
        fov = params["fov_deg"]
        return (fov * (1 - FOV_DEG_TOLERANCE), fov * (1 + FOV_DEG_TOLERANCE))
    return tuple(params["fov_range_deg"])


def database_hashes(cells: list[Cell]) -> list[str]:
    """Cache keys (hashes of their inputs) of the pattern databases the cells' solves load."""
    from ... import cache
    from ...identify import DB_KIND, DB_VERSION, database_settings_for

    keys = set()
    for cell in cells:
        fov_range = _fov_range(cell.params)
        if fov_range is not None:
            settings = database_settings_for(fov_range)
            keys.add(cache.input_key(DB_KIND, DB_VERSION, asdict(settings)))
    return sorted(keys)


def provenance(cells: list[Cell]) -> dict[str, Any]:
    """The provenance part of a manifest."""
    return {"package_version": __version__, "git_commit": git_commit(), "catalog_hash": catalog_hash(),
            "database_hashes": database_hashes(cells), "driver_host": socket.gethostname()}
