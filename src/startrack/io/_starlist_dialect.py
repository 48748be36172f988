"""How the lines of a star list split into fields: the separators and comments of the CSV files
people write by hand, export from a spreadsheet or get from another program.

* The separator is the header row's: a comma, else a tab, else a semicolon, else runs of blanks
  (``x y flux``). With a tab or a semicolon, a number's decimal comma (``12,5``, as a spreadsheet
  in many locales writes it) is read as a point.
* ``#`` starts a comment, on a line of its own or after the fields of a row (``x,y,flux # px``);
  a field that holds one is quoted (``"HIP #5"``).
* A header written as a comment (``# x y flux``, as some programs write it) is taken as the header
  when the first row that is not a comment holds only numbers.
* SExtractor's ``ASCII_HEAD`` catalogs name one column per comment line (``#   3 X_IMAGE  Object
  position along x  [pixel]``, 1-based column numbers; a vector column such as ``FLUX_APER`` of
  three apertures spans the numbers up to the next line's): :func:`sextractor_names`.
"""

from __future__ import annotations

import csv
import itertools
import re

SEPARATORS = (",", "\t", ";")
"""The separators looked for in the header row, in this order; none of them: runs of blanks."""

DECIMAL_COMMA_SEPARATORS = ("\t", ";")
"""Separators beside which a comma in a number is a decimal comma."""


def without_comment(line: str) -> str:
    """``line`` up to its first ``#`` outside double quotes (the whole line when it has none):
    a quoted field may hold one (``"HIP #5"``)."""
    if '"' not in line:
        return line.split("#", 1)[0]
    quoted = False
    for k, char in enumerate(line):
        if char == '"':
            quoted = not quoted
        elif char == "#" and not quoted:
            return line[:k]
    return line


def separator_of(header: str) -> str | None:
    """The separator of a list whose header row is ``header``; None for runs of blanks."""
    return next((sep for sep in SEPARATORS if sep in header), None)


def split_rows(lines: list[str], separator: str | None) -> list[list[str]]:
    """Each line's fields (the lines hold no comment); with a tab or a semicolon, a comma in a
    field is turned into a decimal point.

    Raises
    ------
    csv.Error
        A field's quotes are broken.
    """
    if separator is None:
        return [line.split() for line in lines]
    rows = list(csv.reader(lines, delimiter=separator))
    if separator in DECIMAL_COMMA_SEPARATORS:
        rows = [[field.replace(",", ".") for field in row] for row in rows]
    return rows


def is_numeric_row(fields: list[str]) -> bool:
    """Whether every field of a row reads as a number."""
    try:
        [float(field) for field in fields]
    except ValueError:
        return False
    return bool(fields)


_SEXTRACTOR_LINE = re.compile(r"^\s*#\s*(\d+)\s+([A-Za-z_][\w.\-]*)(?:\s|$)")


def sextractor_names(comments: list[str], n_fields: int) -> list[str] | None:
    """The column names of an ``ASCII_HEAD`` header (lower case), or None when ``comments`` (the
    comment lines before the first row, with their ``#``) are not one.

    Every comment line must read ``# <number> <NAME> ...`` with the numbers rising from 1; the
    columns of a vector entry after its first (up to the next number, or to ``n_fields``, the
    first row's fields, for the last entry) are named ``<name>_2``, ``<name>_3``, ...
    """
    matches = [_SEXTRACTOR_LINE.match(line) for line in comments]
    entries = [(int(m.group(1)), m.group(2).lower()) for m in matches if m]
    if not entries or len(entries) != len(comments):
        return None
    numbers = [number for number, _ in entries]
    if numbers[0] != 1 or any(b <= a for a, b in itertools.pairwise(numbers)) or numbers[-1] > n_fields:
        return None
    names: list[str] = []
    for (number, name), end in zip(entries, [*numbers[1:], n_fields + 1], strict=True):
        names += [name] + [f"{name}_{k}" for k in range(2, end - number + 1)]
    return names
