"""Shared fixtures: the real sky images in ../shared/realdata and their astrometry.net truth."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

REALDATA_DIR = Path(__file__).resolve().parents[1].parent / "shared" / "realdata"
"""``<repo>/../shared/realdata`` (see its README.md); never copied into the repository."""


@pytest.fixture(scope="session")
def realdata_dir() -> Path:
    """Path of the real-image folder; skips the test when it is absent."""
    if not (REALDATA_DIR / "truth.csv").is_file():
        pytest.skip(f"real-image folder {REALDATA_DIR} (with truth.csv) is absent")
    return REALDATA_DIR


@pytest.fixture(scope="session")
def truth_table(realdata_dir: Path) -> list[dict[str, str]]:
    """Rows of realdata/truth.csv as dicts of column name -> text (convert as needed)."""
    with open(realdata_dir / "truth.csv", newline="") as fh:
        return list(csv.DictReader(fh))
