"""Star lists: CSV files of measured star positions in our pixel convention.

Format: a header row naming the columns, then one star per row, comma-separated. Column names
are matched without regard to case or surrounding spaces; lines starting with ``#`` are
comments. Required columns ``x`` and ``y`` are 0-based pixel-centre coordinates (x = column,
y = row; see :mod:`startrack.conventions`; subtract 1 from FITS / astrometry.net positions).
Optional columns ``flux`` (any linear unit) and ``mag`` are read when present; other columns are
ignored. Every value read must be a finite number. Lines are read one at a time, at most
:data:`MAX_LINE_CHARS` characters each, and at most :data:`MAX_STARS` rows.
"""

from __future__ import annotations

import csv
import itertools
import math
import os
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidInputError
from ._targets import note_input

REQUIRED_COLUMNS = ("x", "y")
OPTIONAL_COLUMNS = ("flux", "mag")


MAX_LINE_CHARS = 4096
"""Longest line read (a row of numbers needs far less); a longer one is refused, not parsed."""

MAX_STARS = 1_000_000
"""Most data rows read; a longer list is refused."""


def _lines(path: Path) -> list[tuple[int, str]]:
    """The (line number, text) of the non-blank, non-comment lines, each at most MAX_LINE_CHARS long."""
    lines: list[tuple[int, str]] = []
    with open(path, newline="", encoding="utf-8-sig") as fh:
        for number in itertools.count(1):
            line = fh.readline(MAX_LINE_CHARS + 1)
            if not line:
                return lines
            if len(line) > MAX_LINE_CHARS or (len(line) == MAX_LINE_CHARS and not line.endswith("\n")):
                raise InvalidInputError(f"star list {path}, line {number}: longer than {MAX_LINE_CHARS} "
                                        "characters; a row holds x, y and a few numbers")
            if line.strip() and not line.lstrip().startswith("#"):
                lines.append((number, line))
                if len(lines) > MAX_STARS + 1:
                    raise InvalidInputError(f"star list {path} has more than {MAX_STARS:,} rows")
    return lines


def _rows(path: Path) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header names (lower case) and the (line number, fields) of each data row."""
    note_input(path)
    try:
        lines = _lines(path)
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"star list {path} is not a UTF-8 text CSV file (undecodable byte at offset "
                                f"{exc.start})") from None
    except OSError as exc:
        raise InvalidInputError(f"star list {path} cannot be read ({exc.strerror or exc})") from None
    if not lines:
        raise InvalidInputError(f"star list {path} is empty: expected a header row with x, y")
    try:
        parsed = list(csv.reader(line for _, line in lines))
    except csv.Error as exc:
        raise InvalidInputError(f"star list {path} is not a valid CSV file ({exc})") from None
    if len(parsed) != len(lines):
        raise InvalidInputError(f"star list {path}: a quoted field runs over several lines; give one star per line")
    names = [name.strip().lower() for name in parsed[0]]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise InvalidInputError(f"star list {path}: duplicate column(s) {duplicates}")
    return names, [(n, fields) for (n, _), fields in zip(lines[1:], parsed[1:], strict=True)]


def _number(text: str, path: Path, line: int, column: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InvalidInputError(
            f"star list {path}, line {line}, column {column!r}: {text.strip()!r} is not a number"
        ) from None
    if not math.isfinite(value):
        raise InvalidInputError(
            f"star list {path}, line {line}, column {column!r}: value is {text.strip()!r}; "
            "every value must be a finite number (no NaN or inf)"
        )
    return value


def read_star_list(path: str | os.PathLike) -> dict[str, NDArray[np.float64]]:
    """Read a CSV star list.

    Parameters
    ----------
    path : str or Path
        The CSV file (format in the module docstring).

    Returns
    -------
    dict of str -> ndarray, shape (N,), float64
        ``"x"`` and ``"y"`` in pixels (0-based, pixel centres), plus ``"flux"`` and ``"mag"``
        when the file has them. N may be 0 (a header with no rows).

    Raises
    ------
    InvalidInputError
        If the file is missing or empty, lacks x or y, has a row of the wrong length, or holds
        a value that is not a finite number; the message names the file, line and column.
    """
    if not isinstance(path, str | os.PathLike):
        raise InvalidInputError(f"path must be a file name (str or os.PathLike), got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise InvalidInputError(f"star list {path} does not exist or is not a file")
    names, rows = _rows(path)
    missing = [c for c in REQUIRED_COLUMNS if c not in names]
    if missing:
        raise InvalidInputError(
            f"star list {path} lacks required column(s) {missing}; found columns {names}"
        )
    wanted = [c for c in (*REQUIRED_COLUMNS, *OPTIONAL_COLUMNS) if c in names]
    values: dict[str, list[float]] = {c: [] for c in wanted}
    for line, fields in rows:
        if len(fields) != len(names):
            raise InvalidInputError(
                f"star list {path}, line {line}: {len(fields)} fields, expected {len(names)}"
            )
        for column in wanted:
            values[column].append(_number(fields[names.index(column)], path, line, column))
    return {c: np.asarray(v, dtype=np.float64) for c, v in values.items()}
