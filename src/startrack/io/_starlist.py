"""Star lists: CSV files of measured star positions in our pixel convention, and the catalogs
of SExtractor and astrometry.net.

Format: UTF-8 text (or UTF-16 with its byte-order mark), a header row naming the columns, then
one star per row. Column names are matched
without regard to case or surrounding spaces. The separator is the header's (a comma, a tab, a
semicolon or blanks), ``#`` starts a comment, and a header may be written as the comment line
just before the first row, or as SExtractor's ``ASCII_HEAD`` comments (:mod:`._starlist_dialect`).
Required columns ``x`` and ``y`` are 0-based pixel-centre coordinates (x = column, y = row; see
:mod:`startrack.conventions`); they may also be named as in :data:`COLUMN_NAMES` (``x_px``,
``xcentroid``, ``col``, ...). Positions named as 1-based (:data:`ONE_BASED_NAMES`: SExtractor's
``X_IMAGE``, astrometry.net's ``field_x``) are read when no 0-based pair is there, 1 subtracted.
A FITS file is read as a table (:mod:`._starlist_fits`: astrometry.net's xylists, SExtractor's
``FITS_LDAC``), where ``X`` and ``Y`` are 1-based as well. Optional columns ``flux`` (any linear
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
from ._starlist_dialect import is_numeric_row, separator_of, sextractor_names, split_rows, without_comment
from ._starlist_fits import image_size, is_fits, read_fits_table
from ._targets import note_input

REQUIRED_COLUMNS = ("x", "y")
OPTIONAL_COLUMNS = ("flux", "mag")
COLUMN_NAMES = {
    "x": ("x", "x_px", "x_pix", "xpix", "xcentroid", "x_centroid", "col", "column"),
    "y": ("y", "y_px", "y_pix", "ypix", "ycentroid", "y_centroid", "row"),
    "flux": ("flux", "intensity", "counts", "brightness", "flux_auto", "flux_iso", "flux_best", "flux_win",
             "flux_aper"),
    "mag": ("mag", "magnitude", "mag_auto", "mag_best", "mag_iso", "mag_aper"),
}
"""The names each column is found by (lower case), the first present taken: ``x`` and ``y`` as
named by photutils (``xcentroid``), by a pixel grid (``col``, ``row``), with a unit; the
brightness as SExtractor and others name it."""
ONE_BASED_NAMES = {"x": ("xwin_image", "x_image", "field_x"), "y": ("ywin_image", "y_image", "field_y")}
"""Names of 1-based positions (FITS pixel coordinates, 1 at the first pixel's centre), the first
present taken: SExtractor's windowed and isophotal centroids, astrometry.net's ``field_x``
(its ``corr`` files). In a FITS table ``x`` and ``y`` are 1-based too (:mod:`._starlist_fits`)."""


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


def _lines(path: Path) -> tuple[list[tuple[int, str]], list[str]]:
    """The (line number, text) of the lines that hold fields (comments removed), each at most
    MAX_LINE_CHARS long; and the comment lines before the first of them (a header written as
    comments), with their ``#``."""
    lines: list[tuple[int, str]] = []
    comments: list[str] = []
    with open(path, newline="", encoding=_encoding(path)) as fh:
        for number in itertools.count(1):
            line = fh.readline(MAX_LINE_CHARS + 1)
            if not line:
                return lines, comments
            if len(line) > MAX_LINE_CHARS or (len(line) == MAX_LINE_CHARS and not line.endswith("\n")):
                raise InvalidInputError(f"star list {path}, line {number}: longer than {MAX_LINE_CHARS} "
                                        "characters; a row holds x, y and a few numbers")
            text = without_comment(line).strip()
            if text:
                lines.append((number, text))
                if len(lines) > MAX_STARS + 1:
                    raise InvalidInputError(f"star list {path} has more than {MAX_STARS:,} rows")
            elif not lines and line.lstrip().startswith("#"):
                comments.append(line.strip())
    return lines, comments


def _read_lines(path: Path) -> tuple[list[tuple[int, str]], list[str]]:
    """:func:`_lines`, its failures said as a star list's."""
    try:
        lines, comments = _lines(path)
    except UnicodeDecodeError as exc:
        raise InvalidInputError(f"star list {path} is not a text CSV file in UTF-8 or UTF-16 (undecodable byte "
                                f"at offset {exc.start}); save it as UTF-8") from None
    except OSError as exc:
        raise InvalidInputError(f"star list {path} cannot be read ({exc.strerror or exc})") from None
    if not lines:
        raise InvalidInputError(f"star list {path} is empty: expected a header row with x, y")
    return lines, comments


def _rows(path: Path) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header names (lower case) and the (line number, fields) of each data row."""
    note_input(path)
    lines, comments = _read_lines(path)
    texts = [text for _, text in lines]
    numbered = lines
    first = texts[0].split()
    sextractor = sextractor_names(comments, len(first)) if is_numeric_row(first) else None
    if sextractor is not None:  # SExtractor's ASCII_HEAD: one comment line per column, blank-separated rows
        return sextractor, list(zip((n for n, _ in lines), split_rows(texts, None), strict=True))
    header = comments[-1][1:].strip() if comments else ""
    if header and is_numeric_row(split_rows(texts[:1], separator_of(header))[0]):
        texts, numbered = [header, *texts], [(0, header), *lines]  # "# x y flux", then numbers
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


def _first(names: list[str], aliases: tuple[str, ...]) -> int | None:
    """Where the first of ``aliases`` present is among ``names`` (None if none is)."""
    return next((names.index(n) for n in aliases if n in names), None)


def _positions(names: list[str], fits_table: bool = False) -> tuple[dict[str, int], float] | None:
    """Where x and y are among ``names`` and what to subtract from them (0, or 1 for 1-based
    positions: :data:`ONE_BASED_NAMES`, and ``x``, ``y`` in a FITS table); a 0-based pair first.
    None when neither pair is complete."""
    zero = {c: tuple(n for n in COLUMN_NAMES[c] if not (fits_table and n == c)) for c in REQUIRED_COLUMNS}
    one = {c: ONE_BASED_NAMES[c] + ((c,) if fits_table else ()) for c in REQUIRED_COLUMNS}
    for aliases, shift in ((zero, 0.0), (one, 1.0)):
        found = {c: _first(names, aliases[c]) for c in REQUIRED_COLUMNS}
        if all(index is not None for index in found.values()):
            return {c: int(index) for c, index in found.items() if index is not None}, shift
    return None


def _columns(path: Path, names: list[str], fits_table: bool = False) -> tuple[dict[str, int], float]:
    """Where each column of :data:`COLUMN_NAMES` present is among ``names``, and what to subtract
    from x and y (:func:`_positions`).

    Raises
    ------
    InvalidInputError
        x or y is missing (naming the columns found and the names looked for).
    """
    positions = _positions(names, fits_table)
    if positions is None:
        missing = [c for c in REQUIRED_COLUMNS if _first(names, COLUMN_NAMES[c]) is None]
        also = "; ".join(f"{c} may also be named {', '.join(COLUMN_NAMES[c][1:])}, or 1-based "
                         f"{', '.join(ONE_BASED_NAMES[c])}" for c in missing)
        numbers = "; its first row holds numbers: start it with a header row such as x,y,flux" \
            if is_numeric_row(names) else ""
        bases = [any(_first(names, aliases[c]) is not None for c in REQUIRED_COLUMNS)
                 for aliases in (COLUMN_NAMES, ONE_BASED_NAMES)]
        mixed = "; x and y must be both 0-based or both 1-based" if all(bases) else ""
        raise InvalidInputError(f"star list {path} lacks required column(s) {missing}; found columns {names} "
                                f"({also}){numbers}{mixed}")
    columns, shift = positions
    brightness = {c: _first(names, COLUMN_NAMES[c]) for c in OPTIONAL_COLUMNS}
    return {**columns, **{c: index for c, index in brightness.items() if index is not None}}, shift


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
    """Read a star list: a CSV file, a SExtractor catalog or a FITS table.

    Parameters
    ----------
    path : str or Path
        The file (formats in the module docstring); a FITS file is known by its first bytes.

    Returns
    -------
    dict of str -> ndarray, shape (N,), float64
        ``"x"`` and ``"y"`` in pixels (0-based, pixel centres; 1 subtracted from 1-based
        positions), plus ``"flux"`` and ``"mag"`` when the file has them. N may be 0 (a header
        with no rows).

    Raises
    ------
    InvalidInputError
        If the file is missing or empty, lacks x or y, has a row of the wrong length, or holds
        a value that is not a finite number; the message names the file, line (or table row)
        and column.
    """
    if not isinstance(path, str | os.PathLike):
        raise InvalidInputError(f"path must be a file name (str or os.PathLike), got {type(path).__name__}")
    path = Path(path)
    if not path.is_file():
        raise InvalidInputError(f"star list {path} does not exist or is not a file")
    try:
        fits_file = is_fits(path)
    except OSError as exc:
        raise InvalidInputError(f"star list {path} cannot be read ({exc.strerror or exc})") from None
    if fits_file:
        return _from_fits(path)
    names, rows = _rows(path)
    columns, shift = _columns(path, names)
    values: dict[str, list[float]] = {c: [] for c in columns}
    for line, fields in rows:
        if len(fields) != len(names):
            raise InvalidInputError(
                f"star list {path}, line {line}: {len(fields)} fields, expected {len(names)}"
            )
        for column, index in columns.items():
            values[column].append(_number(fields[index], path, line, names[index]))
    return _shifted({c: np.asarray(v, dtype=np.float64) for c, v in values.items()}, shift)


def _from_fits(path: Path) -> dict[str, NDArray[np.float64]]:
    """:func:`read_star_list` of a FITS table (:mod:`._starlist_fits`)."""
    note_input(path)
    names, table, numeric = read_fits_table(path, lambda found: _positions(found, fits_table=True) is not None,
                                            MAX_STARS)
    columns, shift = _columns(path, names, fits_table=True)
    text = [names[index] for index in columns.values() if not numeric[index]]
    if text:
        raise InvalidInputError(f"star list {path}: column(s) {text} hold text, not numbers")
    out = {c: table[:, index].copy() for c, index in columns.items()}
    for column, index in columns.items():
        bad = np.flatnonzero(~np.isfinite(out[column]))
        if bad.size:
            raise InvalidInputError(f"star list {path}, table row {bad[0] + 1}, column {names[index]!r}: value is "
                                    f"{out[column][bad[0]]}; every value must be a finite number (no NaN or inf)")
    return _shifted(out, shift)


def _shifted(stars: dict[str, NDArray[np.float64]], shift: float) -> dict[str, NDArray[np.float64]]:
    """``stars`` with ``shift`` subtracted from x and y (1-based positions made 0-based)."""
    if shift:
        stars["x"], stars["y"] = stars["x"] - shift, stars["y"] - shift
    return stars


def star_list_image_size(path: str | os.PathLike) -> tuple[int, int] | None:
    """The (width, height) in pixels of the image a star list was measured on, when the file says
    so: astrometry.net's ``.axy`` (``IMAGEW``, ``IMAGEH``); None otherwise (a CSV never does)."""
    return image_size(path)
