"""Every ``from startrack... import name`` written anywhere in the project (code, code inside
strings that a benchmark or a test runs in a new process, the docs' examples) names a module or
an attribute that exists: a module renamed or a name moved leaves no statement behind that only
fails when that one benchmark or page is run."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FROM_IMPORT = re.compile(r"from (startrack(?:\.\w+)*) import \(?([\w, ]+)")
FILES = sorted(p for folder in ("src", "tests", "benchmarks", "scripts", "docs") for p in (ROOT / folder).rglob("*")
               if p.suffix in {".py", ".md"} and ".venv" not in str(p.relative_to(ROOT)))
DELIBERATELY_MISSING = {("startrack", "no_such_name")}
"""Statements that name a missing name on purpose (a test of the error)."""


def _missing(text: str, where: str) -> list[str]:
    """``where:line: module has no name`` for each imported name of ``text`` that does not exist."""
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        for match in FROM_IMPORT.finditer(line):
            module = importlib.import_module(match.group(1))
            for name in (part.strip().split(" as ")[0] for part in match.group(2).split(",")):
                if name and (match.group(1), name) not in DELIBERATELY_MISSING and not hasattr(module, name):
                    try:
                        importlib.import_module(f"{match.group(1)}.{name}")
                    except ModuleNotFoundError:
                        found.append(f"{where}:{number}: {match.group(1)} has no {name}")
    return found


@pytest.mark.parametrize("folder", ["src", "tests", "benchmarks", "scripts", "docs"])
def test_every_startrack_import_names_what_exists(folder):
    missing = [m for path in FILES if path.relative_to(ROOT).parts[0] == folder
               for m in _missing(path.read_text(encoding="utf-8"), str(path.relative_to(ROOT)))]
    assert not missing


def test_the_scan_finds_a_wrong_name():
    statement = "from startrack.identify " + "import quad_kernel, match_lost_in_space"  # split: not a hit here
    page = f"```python\n{statement}\n```\n"
    assert _missing(page, "page.md") == ["page.md:2: startrack.identify has no quad_kernel"]
