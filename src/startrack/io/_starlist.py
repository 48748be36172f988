"""Star lists: CSV files of measured star positions in our pixel convention.

Format: UTF-8 text (or UTF-16 with its byte-order mark), a header row naming the columns, then
one star per row. Column names are matched
without regard to case or surrounding spaces. The separator is the header's (a comma, a tab, a
semicolon or blanks), ``#`` starts a comment, and a header may be written as the comment line
just before the first row (:mod:`._starlist_dialect`). Required columns ``x`` and ``y`` are
0-based pixel-centre coordinates (x = column, y = row; see :mod:`startrack.conventions`;
subtract 1 from FITS, SExtractor or astrometry.net positions); they may also be named as in
:data:`COLUMN_NAMES` (``x_px``, ``xcentroid``, ``col``, ...). Optional columns ``flux`` (any linear
unit) and ``mag`` are read when present; other columns are ignored. Every value read must be a
finite number. Lines are read one at a time, at most :data:`MAX_LINE_CHARS` characters each, and
at most :data:`MAX_STARS` rows.
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
from ._starlist_dialect import is_numeric_row, separator_of, split_rows, without_comment
from ._targets import note_input

REQUIRED_COLUMNS = ("x", "y")
OPTIONAL_COLUMNS = ("flux", "mag")
COLUMN_NAMES = {
    "x": ("x", "x_px", "x_pix", "xpix", "xcentroid", "x_centroid", "col", "column"),
    "y": ("y", "y_px", "y_pix", "ypix", "ycentroid", "y_centroid", "row"),
    "flux": ("flux", "intensity", "counts", "brightness", "flux_auto", "flux_iso"),
    "mag": ("mag", "magnitude", "mag_auto"),
}
"""The names each column is found by (lower case), the first present taken: ``x`` and ``y`` as
named by photutils (``xcentroid``), by a pixel grid (``col``, ``row``), with a unit; the
brightness as SExtractor and others name it."""
ONE_BASED_COLUMNS = ("x_image", "y_image", "field_x", "field_y")
"""Columns of 1-based positions (SExtractor's X_IMAGE, astrometry.net's field_x): refused with a
message, since reading them as ours would put every star a pixel off."""


MAX_LINE_CHARS = 4096
"""Longest line read (a row of numbers needs far less); a longer one is refused, not parsed."""

MAX_STARS = 1_000_000
"""Most data rows read; a longer list is refused."""


def _encoding(path: Path) -> str:
    """UTF-16 for a file that starts with its byte-order mark (a spreadsheet's "Unicode text"),
    else UTF-8 (with or without a mark)."""
    with open(path, "rb") as fh:
        start = fh.read(2)
    return "utf-16" if start in (b"\xff\xfe", b"\xfe\xff") else "utf-8-sig"


def _lines(path: Path) -> tuple[list[tuple[int, str]], str | None]:
    """The (line number, text) of the lines that hold fields (comments removed), each at most
    MAX_LINE_CHARS long; and the last comment line before the first of them (a header written as
    a comment), without its ``#``."""
    lines: list[tuple[int, str]] = []
    comment_header = None
    with open(path, newline="", encoding=_encoding(path)) as fh:
        for number in itertools.count(1):
            line = fh.readline(MAX_LINE_CHARS + 1)
            if not line:
                return lines, comment_header
            if len(line) > MAX_LINE_CHARS or (len(line) == MAX_LINE_CHARS and not line.endswith("\n")):
                raise InvalidInputError(f"star list {path}, line {number}: longer than {MAX_LINE_CHARS} "
                                        "characters; a row holds x, y and a few numbers")
            text = without_comment(line).strip()
            if text:
                lines.append((number, text))
                if len(lines) > MAX_STARS + 1:
                    raise InvalidInputError(f"star list {path} has more than {MAX_STARS:,} rows")
            elif not lines and line.lstrip().startswith("#"):
                comment_header = line.lstrip()[1:].strip()
    return lines, comment_header


def _rows(path: Path) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header names (lower case) and the (line number, fields) of each data row."""
    note_input(path)
    try:
        lines, comment_header = _lines(path)
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"star list {path} is not a text CSV file in UTF-8 or UTF-16 (undecodable byte "
                                f"at offset {exc.start}); save it as UTF-8") from None
    except OSError as exc:
        raise InvalidInputError(f"star list {path} cannot be read ({exc.strerror or exc})") from None
    if not lines:
        raise InvalidInputError(f"star list {path} is empty: expected a header row with x, y")
    texts = [text for _, text in lines]
    numbered = lines
    if comment_header and is_numeric_row(split_rows(texts[:1], separator_of(comment_header))[0]):
        texts, numbered = [comment_header, *texts], [(0, comment_header), *lines]  # "# x y flux", then numbers
    separator = separator_of(texts[0])
    try:
        parsed = split_rows(texts, separator)
    except csv.Error as exc:
        raise InvalidInputError(f"star list {path} is not a valid CSV file ({exc})") from None
    if len(parsed) != len(texts):
        raise InvalidInputError(f"star list {path}: a quoted field runs over several lines; give one star per line")
    names = [name.strip().lower() for name in parsed[0]]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise InvalidInputError(f"star list {path}: duplicate column(s) {duplicates}")
    return names, [(n, fields) for (n, _), fields in zip(numbered[1:], parsed[1:], strict=True)]


def _columns(path: Path, names: list[str]) -> dict[str, int]:
    """Where each column of :data:`COLUMN_NAMES` present is among ``names``.

    Raises
    ------
    InvalidInputError
        x or y is missing (naming the columns found and the names looked for), or the positions
        are 1-based (:data:`ONE_BASED_COLUMNS`).
    """
    found = {column: next((names.index(n) for n in aliases if n in names), None)
             for column, aliases in COLUMN_NAMES.items()}
    one_based = [n for n in names if n in ONE_BASED_COLUMNS]
    if found["x"] is None and one_based:
        raise InvalidInputError(f"star list {path}: columns {one_based} hold 1-based positions; give x and y "
                                "columns of 0-based pixel centres (subtract 1)")
    missing = [c for c in REQUIRED_COLUMNS if found[c] is None]
    if missing:
        also = "; ".join(f"{c} may also be named {', '.join(COLUMN_NAMES[c][1:])}" for c in missing)
        numbers = "; its first row holds numbers: start it with a header row such as x,y,flux" \
            if is_numeric_row(names) else ""
        raise InvalidInputError(f"star list {path} lacks required column(s) {missing}; found columns {names} "
                                f"({also}){numbers}")
    return {column: index for column, index in found.items() if index is not None}


def _number(text: str, path: Path, line: int, column: str) -> float:
    """The number a cell holds; Python's digit separators ("1_000") are not a number in a table."""
    try:
        if "_" in text:
            raise ValueError(text)
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
    columns = _columns(path, names)
    values: dict[str, list[float]] = {c: [] for c in columns}
    for line, fields in rows:
        if len(fields) != len(names):
            raise InvalidInputError(
                f"star list {path}, line {line}: {len(fields)} fields, expected {len(names)}"
            )
        for column, index in columns.items():
            values[column].append(_number(fields[index], path, line, names[index]))
    return {c: np.asarray(v, dtype=np.float64) for c, v in values.items()}
