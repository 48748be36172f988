"""Reading a campaign output folder safely: the shape of ``manifest.json`` and the trial parts.

Every command that reads a folder (``report``, ``rerun``, ``run --resume``) reads it through
:func:`load_manifest` and :func:`read_parts`, so that a damaged folder (a manifest that is not
JSON or not of the campaign's shape, a part that is not Parquet or lacks a column) is refused
with one line naming the file and what to do, before anything is run or written.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from ...errors import InvalidInputError
from ._outcome import COLUMNS

FORMAT = "startrack-campaign/1"
"""The output-folder format this package writes and reads (docs/campaigns.md)."""
PART = re.compile(r"part-(\d+)-(\d+)\.parquet")
"""The name of a trial part, ``part-CCCCC-KKKKKK.parquet`` (cell C, first trial K)."""

Shape = Any
"""What a manifest value must be: a type or tuple of types, ``[shape]`` (a list of such items) or
``{key: (shape, required)}`` (an object with those keys)."""
_NONE = type(None)
_CELL = {"cell": (int, True), "label": (str, False), "params": (dict, True), "source": ((str, _NONE), False)}
_SPEC = {"campaign": (dict, False), "reference": ([dict], False)}
_CASE = {"name": (str, True), "baseline": (int, True), "all": (int, True), "sources": (dict, True),
        "off": (dict, True), "on": (dict, True)}
_BUDGET = {"cases": ([_CASE], True), "fields": (int, True), "dithers": (int, True), "repeats": (int, True)}
_MANIFEST: dict[str, tuple[Shape, bool]] = {
    "name": (str, True), "level": (str, True), "mode": (str, False), "spec": (_SPEC, True), "spec_text": (str, True),
    "swept": ([str], False), "trials_per_cell": (int, True), "cells": ([_CELL], True), "correct": (dict, False),
    "chunk_size": (int, True), "started_utc": ((str, _NONE), False), "finished_utc": ((str, _NONE), False),
    "runs": ([{"hosts": ([str], False)}], False), "driver_host": (str, False), "hosts": ([str], False),
    "budget": (_BUDGET, False),
}
"""The keys of ``manifest.json`` that the campaign code reads, and their shapes (the others are shown as they are)."""
_AGAIN = "run the spec again into a new --out folder"
_NAMES = {dict: "an object", list: "a list", str: "a string", int: "an integer", float: "a number",
         bool: "true or false", _NONE: "null"}


def _describe(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    return _NAMES.get(type(value), type(value).__name__)


def _want(shape: Shape) -> str:
    if isinstance(shape, dict):
        return _NAMES[dict]
    if isinstance(shape, list):
        return _NAMES[list]
    types = shape if isinstance(shape, tuple) else (shape,)
    return " or ".join(_NAMES.get(t, t.__name__) for t in types)


def _fits(value: Any, shape: Shape) -> bool:
    if isinstance(shape, dict | list):
        return isinstance(value, type(shape))
    types = shape if isinstance(shape, tuple) else (shape,)
    return isinstance(value, types) and not (isinstance(value, bool) and bool not in types)


def _check(value: Any, shape: Shape, where: str) -> str | None:
    """What is wrong with ``value`` (at ``where``) for ``shape``, or None."""
    if not _fits(value, shape):
        return f"{where} must be {_want(shape)}, got {_describe(value)}"
    if isinstance(shape, list):
        for i, item in enumerate(value):
            if (problem := _check(item, shape[0], f"{where}[{i}]")) is not None:
                return problem
    elif isinstance(shape, dict):
        for key, (sub, required) in shape.items():
            name = f"{where}.{key}" if where else key
            if key not in value:
                if required:
                    return f"{name} is missing (it must be {_want(sub)})"
            elif (problem := _check(value[key], sub, name)) is not None:
                return problem
    return None


def check_manifest(manifest: Any, path: Path) -> dict[str, Any]:
    """``manifest`` itself when it has the shape the campaign code needs (:data:`_MANIFEST`).

    Raises
    ------
    InvalidInputError
        Naming ``path`` and the first thing wrong, if it is not an object of format :data:`FORMAT`
        with every key of :data:`_MANIFEST` of its shape.
    """
    if not isinstance(manifest, dict):
        raise InvalidInputError(f"{path} must hold a JSON object (the campaign's manifest), got "
                                f"{_describe(manifest)}; the folder is damaged: {_AGAIN}")
    if manifest.get("format") != FORMAT:
        raise InvalidInputError(f"{path}: format {manifest.get('format')!r}, expected {FORMAT!r}")
    problem = _check(manifest, _MANIFEST, "")
    if problem is None and manifest["chunk_size"] < 1:
        problem = f"chunk_size must be at least 1, got {manifest['chunk_size']}"
    if problem is not None:
        raise InvalidInputError(f"{path} is damaged: {problem}; {_AGAIN}")
    return manifest


def load_manifest(out: Path) -> dict[str, Any]:
    """The checked ``manifest.json`` of the campaign folder ``out`` (:func:`check_manifest`).

    Raises
    ------
    InvalidInputError
        If the file is missing or unreadable, not JSON, or not of the manifest's shape.
    """
    path = out / "manifest.json"
    try:
        data = path.read_bytes()
    except OSError as exc:
        if not path.exists() and part_paths(out / "trials"):
            raise InvalidInputError(f"{out} is damaged: it holds trial parts but no manifest.json; {_AGAIN}") from None
        raise InvalidInputError(f"{out} is not a campaign output folder (no readable manifest.json: {exc})") from None
    try:
        manifest = json.loads(data.decode("utf-8"))
    except ValueError as exc:  # UnicodeDecodeError included
        raise InvalidInputError(f"{path} is not valid UTF-8 JSON ({exc}); the folder is damaged: {_AGAIN}") from None
    return check_manifest(manifest, path)


def part_paths(trials_dir: Path) -> list[Path]:
    """The trial parts (:data:`PART`) in ``trials_dir``, sorted (none when the folder is missing).

    Raises
    ------
    InvalidInputError
        If ``trials_dir`` exists but is not a folder.
    """
    if not trials_dir.exists():
        return []
    if not trials_dir.is_dir():
        raise InvalidInputError(f"{trials_dir} is not a folder (it should hold the trial parts); {_AGAIN}")
    return sorted(p for p in trials_dir.iterdir() if PART.fullmatch(p.name))


def part_key(path: Path) -> tuple[int, int]:
    """(cell, first trial) of the part ``path``."""
    match = PART.fullmatch(path.name)
    if match is None:
        raise InvalidInputError(f"{path} is not named part-CCCCC-KKKKKK.parquet")
    return int(match[1]), int(match[2])


def _kind(dtype: pa.DataType) -> str:
    for name, test in (("integer", pa.types.is_integer), ("floating-point", pa.types.is_floating),
                       ("boolean", pa.types.is_boolean), ("string", pa.types.is_string),
                       ("string", pa.types.is_large_string)):
        if test(dtype):
            return name
    return str(dtype)


def _schema_problem(schema: pa.Schema) -> str | None:
    for name, dtype in COLUMNS.items():
        if name not in schema.names:
            return f"it has no column {name!r}"
        found = schema.field(name).type
        if _kind(found) != _kind(dtype):
            return f"its column {name!r} is {found}, expected {_kind(dtype)}"
    return None


def _damaged(path: Path, problem: str) -> InvalidInputError:
    out = path.parent.parent
    return InvalidInputError(f"{path} is damaged ({problem}): remove it and run 'startrack campaign run _SPEC --out "
                             f"{out} --resume' to run its chunk again, or {_AGAIN}")


def _reason(exc: Exception) -> str:
    """The gist of a pyarrow error: its first sentence, without the prefixes that repeat the path."""
    text = str(exc).strip()
    return text.splitlines()[0].rsplit("': ", 1)[-1].split(". ")[0].rstrip(".") if text else type(exc).__name__


def _unreadable(exc: Exception) -> str:
    return f"not a readable Parquet file: {_reason(exc)}"


def check_parts(parts: list[Path], *, full: bool = False) -> None:
    """Refuse the first of ``parts`` that does not read (its footer; all of it with ``full``)
    or lacks a column of every trial table (:data:`COLUMNS`).

    Raises
    ------
    InvalidInputError
        Naming the damaged part and what to do.
    """
    for path in parts:
        try:
            schema = pq.read_table(path).schema if full else pq.read_schema(path)
        except (pa.ArrowException, OSError) as exc:
            raise _damaged(path, _unreadable(exc)) from None
        if (problem := _schema_problem(schema)) is not None:
            raise _damaged(path, problem)


def read_parts(out: Path) -> pa.Table:
    """Every trial row of the campaign folder ``out``, sorted by cell and trial.

    Raises
    ------
    InvalidInputError
        If there is no part yet, or a part is damaged (:func:`check_parts`).
    """
    trials_dir = out / "trials"
    parts = part_paths(trials_dir)
    if not parts:
        raise InvalidInputError(f"{out}: no finished trials yet (trials/ holds no part-*.parquet)")
    check_parts(parts)
    try:
        table = pq.read_table([str(p) for p in parts])
    except (pa.ArrowException, OSError) as exc:
        check_parts(parts, full=True)  # names the part that does not read
        raise InvalidInputError(f"{trials_dir}: the parts do not read as one table ({_reason(exc)}); "
                                f"{_AGAIN}") from None
    return table.sort_by([("cell", "ascending"), ("trial", "ascending")])
