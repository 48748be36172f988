"""Every ``from startrack... import name`` written anywhere in the project (code, code inside
strings that a benchmark or a test runs in a new process, the docs' examples) names a module or
an attribute that exists: a module renamed or a name moved leaves no statement behind that only
fails when that one benchmark or page is run."""

from __future__ import annotations

import ast
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


def _statements(text: str, is_python: bool) -> list[tuple[int, str, list[str]]]:
    """(line, module, names) of every ``from startrack... import`` in ``text``: the real import
    statements of a Python file (parenthesised ones over several lines too), and any written on one
    line anywhere, which finds those in code strings and in the docs' examples."""
    found = [(number, match.group(1), [part.strip().split(" as ")[0] for part in match.group(2).split(",")])
             for number, line in enumerate(text.splitlines(), 1) for match in FROM_IMPORT.finditer(line)]
    if is_python:
        nodes = [node for node in ast.walk(ast.parse(text)) if isinstance(node, ast.ImportFrom) and not node.level]
        found += [(node.lineno, node.module, [alias.name for alias in node.names]) for node in nodes
                  if (node.module or "").startswith("startrack")]
    return found


def _missing(text: str, where: str, is_python: bool = False) -> list[str]:
    """``where:line: module has no name`` for each imported name of ``text`` that does not exist."""
    found = set()
    for number, module_name, names in _statements(text, is_python):
        module = importlib.import_module(module_name)
        for name in names:
            if name and (module_name, name) not in DELIBERATELY_MISSING and not hasattr(module, name):
                try:
                    importlib.import_module(f"{module_name}.{name}")
                except ModuleNotFoundError:
                    found.add(f"{where}:{number}: {module_name} has no {name}")
    return sorted(found)


@pytest.mark.parametrize("folder", ["src", "tests", "benchmarks", "scripts", "docs"])
def test_every_startrack_import_names_what_exists(folder):
    missing = [m for path in FILES if path.relative_to(ROOT).parts[0] == folder
               for m in _missing(path.read_text(encoding="utf-8"), str(path.relative_to(ROOT)), path.suffix == ".py")]
    assert not missing


def test_the_scan_finds_a_wrong_name():
    statement = "from startrack.identify " + "import quad_kernel, match_lost_in_space"  # split: not a hit here
    page = f"```python\n{statement}\n```\n"
    assert _missing(page, "page.md") == ["page.md:2: startrack.identify has no quad_kernel"]
    source = "from startrack.identify import (\n    match_lost_in_space,\n    quad_" + "kernel,\n)\n"  # over lines
    assert _missing(source, "x.py", is_python=True) == ["x.py:1: startrack.identify has no quad_kernel"]
