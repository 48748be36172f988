"""Shared fixtures: the real sky images in ../shared/realdata and their astrometry.net truth."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest

TEST_CACHE_DIR = Path(__file__).resolve().parents[1] / ".test-cache"
"""The tests' own cache folder (catalog tables, pattern databases, numba's compiled kernels), inside
the checkout and kept between runs so that a run does not rebuild the databases; never the
user's cache. Set here, when pytest imports this file, before any test imports startrack; child
processes (the CLI tests) inherit it."""
os.environ["STARTRACK_CACHE_DIR"] = str(TEST_CACHE_DIR)

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
