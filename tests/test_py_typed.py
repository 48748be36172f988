"""The package says it is typed (PEP 561): ``py.typed`` beside its ``__init__`` and in its package data."""

import tomllib
from pathlib import Path

import startrack

ROOT = Path(__file__).resolve().parents[1]


def test_py_typed_ships_with_the_package():
    assert (Path(startrack.__file__).parent / "py.typed").is_file()
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    assert "py.typed" in data["startrack"]
