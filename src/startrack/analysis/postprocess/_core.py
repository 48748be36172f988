"""The types every post-processing analysis shares: what it is (:class:`AnalysisInfo`), what it
reads (:class:`ResultSet`), what it gives (:class:`AnalysisResult`), and the checking of its
parameters.

An analysis's parameters are declared as ``name -> (type, default, help)``; :func:`check_params`
turns what a caller gave (already typed, from Python or the server's JSON) into the full set,
refusing unknown names, wrong types and values out of range with an
:class:`~startrack.errors.InvalidInputError` that names the parameter and what would be valid.
:func:`parse_param` converts the text of a command line or a form field to the declared type.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ...errors import InvalidInputError
from ...io import atomic_path
from .._records import ImageRecord

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PARAM_TYPES = (int, float, bool, str, list)
"""The parameter types an analysis may declare (a ``list`` holds numbers or strings)."""


@dataclass(frozen=True)
class AnalysisInfo:
    """What an analysis is and what it takes.

    Attributes
    ----------
    name : str
        Its key in :data:`startrack.analysis.postprocess.ANALYSES` (and the CLI's NAME).
    title, description : str
        A heading and a paragraph: what the figure shows and where it comes from in Fowler 2013.
    min_sets, max_sets : int
        How many result sets it takes.
    params : mapping
        ``name -> (type, default, help)``; the type is one of :data:`PARAM_TYPES`, a default of
        None means "not given".
    needs_images : bool
        True when it reads the pixels (each record needs ``image`` or a readable ``path``).
    limits : mapping
        ``name -> (low, high)`` for numeric parameters (None for an open end; for a ``list``, the
        bounds of its length).
    choices : mapping
        ``name -> allowed values`` for string parameters.
    check : callable or None
        ``check(params)`` on the typed, bounded values, for what the type and limits cannot say
        (an odd stamp size, a value the detector refuses); raises InvalidInputError naming the
        parameter, so that the web tool refuses such a request when it is posted, not in its job.
    """

    name: str
    title: str
    description: str
    min_sets: int
    max_sets: int
    params: Mapping[str, tuple[type, Any, str]] = field(default_factory=dict)
    needs_images: bool = False
    limits: Mapping[str, tuple[float | None, float | None]] = field(default_factory=dict)
    choices: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    check: Callable[[dict[str, Any]], None] | None = None


@dataclass(frozen=True)
class ResultSet:
    """A named group of processed images (a folder, a batch, one set of settings)."""

    name: str
    records: tuple[ImageRecord, ...]

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidInputError(f"a result set needs a non-empty name, got {self.name!r}")
        records = tuple(self.records)
        if not all(isinstance(r, ImageRecord) for r in records):
            raise InvalidInputError(f"result set {self.name!r}: records must be ImageRecord objects")
        object.__setattr__(self, "records", records)


@dataclass(frozen=True)
class AnalysisResult:
    """A figure and the numbers behind it.

    Attributes
    ----------
    name, title : str
    figure : matplotlib.figure.Figure
    tables : mapping
        ``table name -> {column -> sequence}``, the columns of a table of one length.
    summary : mapping
        A few headline numbers (``name -> float, int or str``) for a terminal or a page.
    """

    name: str
    title: str
    figure: Figure
    tables: Mapping[str, Mapping[str, Sequence | NDArray]]
    summary: Mapping[str, float | int | str]

    def __post_init__(self) -> None:
        for table, columns in self.tables.items():
            lengths = {len(values) for values in columns.values()}
            if len(lengths) > 1:
                raise ValueError(f"table {table!r} of analysis {self.name!r} has columns of lengths "
                                 f"{sorted(lengths)}; they must be equal")

    def write(self, folder: str | Path) -> list[Path]:
        """Write ``<name>.png`` and ``<name>_<table>.csv`` into ``folder`` (created if missing),
        each file atomically; returns the paths written, the figure first."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        png = folder / f"{self.name}.png"
        with atomic_path(png) as tmp:
            self.figure.savefig(tmp, format="png")
        written = [png]
        for table, columns in self.tables.items():
            path = folder / f"{self.name}_{table}.csv"
            with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
                write_csv(fh, columns)
            written.append(path)
        return written


def write_csv(fh, columns: Mapping[str, Sequence | NDArray]) -> None:
    """Columns as CSV rows: numbers in full precision, NaN and None as empty cells."""
    writer = csv.writer(fh)
    writer.writerow(list(columns))
    for row in zip(*columns.values(), strict=True):
        writer.writerow([csv_cell(v) for v in row])


def csv_cell(value: Any) -> str:
    """One value as CSV text (``repr`` precision for floats, ``true`` / ``false`` for booleans)."""
    if value is None:
        return ""
    if isinstance(value, bool | np.bool_):
        return "true" if value else "false"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return repr(float(value)) if math.isfinite(value) else ""
    return str(value)


def check_sets(info: AnalysisInfo, result_sets: Sequence[ResultSet]) -> tuple[ResultSet, ...]:
    """The result sets as a tuple, refused unless there are ``min_sets`` to ``max_sets`` of them."""
    sets = tuple(result_sets) if not isinstance(result_sets, ResultSet) else (result_sets,)
    if not all(isinstance(s, ResultSet) for s in sets):
        raise InvalidInputError(f"{info.name}: result_sets must be ResultSet objects")
    n_range = (f"exactly {info.min_sets}" if info.min_sets == info.max_sets
               else f"{info.min_sets} to {info.max_sets}")
    if not info.min_sets <= len(sets) <= info.max_sets:
        raise InvalidInputError(f"{info.name} takes {n_range} result set(s), got {len(sets)}")
    for s in sets:
        if not s.records:
            raise InvalidInputError(f"{info.name}: result set {s.name!r} has no images")
    return sets


def check_params(info: AnalysisInfo, params: Mapping[str, Any] | None) -> dict[str, Any]:
    """Every declared parameter with its value (the given one, else the default).

    Raises
    ------
    InvalidInputError
        An unknown name (listing the valid ones), a value of the wrong type, or one outside its
        limits or choices, naming the parameter.
    """
    if params is not None and not isinstance(params, Mapping):
        raise InvalidInputError(f"{info.name}: the parameters must be a mapping of name to value, got {params!r}")
    given = dict(params or {})
    unknown = sorted(set(given) - set(info.params))
    if unknown:
        valid = ", ".join(info.params) or "none"
        raise InvalidInputError(f"{info.name}: unknown parameter {unknown[0]!r}; valid parameters: {valid}")
    out = {}
    for key, (kind, default, _) in info.params.items():
        value = given.get(key, default)
        out[key] = None if value is None else _checked(info, key, kind, value)
    if info.check is not None:
        info.check(out)
    return out


def _checked(info: AnalysisInfo, key: str, kind: type, value: Any) -> Any:
    value = _typed(info.name, key, kind, value)
    low, high = info.limits.get(key, (None, None))
    size = len(value) if kind is list else value
    if kind in (int, float, list) and ((low is not None and size < low) or (high is not None and size > high)):
        what = "length" if kind is list else "value"
        raise InvalidInputError(f"{info.name}: parameter {key!r} must have a {what} within "
                                f"{_bound(low, '-inf')}..{_bound(high, 'inf')}, got {value!r}")
    if kind is str and key in info.choices and value not in info.choices[key]:
        raise InvalidInputError(f"{info.name}: parameter {key!r} must be one of "
                                f"{', '.join(info.choices[key])}, got {value!r}")
    return value


def _bound(value: float | None, open_end: str) -> str:
    return open_end if value is None else f"{value:g}"


def _typed(analysis: str, key: str, kind: type, value: Any) -> Any:
    """``value`` as ``kind`` when it is one (an int is a float too; a tuple is a list)."""
    ok = {int: isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_),
          float: isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool | np.bool_),
          bool: isinstance(value, bool | np.bool_), str: isinstance(value, str),
          list: isinstance(value, list | tuple)}[kind]
    if not ok:
        raise InvalidInputError(f"{analysis}: parameter {key!r} must be {_type_name(kind)}, got {value!r}")
    if kind is float and not math.isfinite(float(value)):
        raise InvalidInputError(f"{analysis}: parameter {key!r} must be a finite number, got {value!r}")
    if kind is list:
        if not all(isinstance(v, int | float | str | bool) for v in value):
            raise InvalidInputError(f"{analysis}: parameter {key!r} must be a list of numbers or strings, "
                                    f"got {value!r}")
        return list(value)
    return kind(value)


def _type_name(kind: type) -> str:
    return {int: "a whole number", float: "a number", bool: "true or false", str: "a string",
            list: "a list"}[kind]


def parse_param(info: AnalysisInfo, key: str, text: str) -> Any:
    """The value of parameter ``key`` from its text (command line ``KEY=VALUE``, a form field).

    Numbers and ``true`` / ``false`` are read as such; a list is comma-separated (``3,4,5``) or
    JSON (``[3, 4, 5]``), each item a number when it reads as one. The result still goes through
    :func:`check_params`.
    """
    if key not in info.params:
        valid = ", ".join(info.params) or "none"
        raise InvalidInputError(f"{info.name}: unknown parameter {key!r}; valid parameters: {valid}")
    kind = info.params[key][0]
    text = text.strip()
    if kind is str:
        return text
    if kind is list:
        if text.startswith("["):
            try:
                return json.loads(text)
            except ValueError:
                raise InvalidInputError(f"{info.name}: parameter {key!r} is not a JSON list: {text!r}") from None
        return [_scalar(item.strip()) for item in text.split(",") if item.strip()]
    value = _scalar(text)
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def _scalar(text: str) -> Any:
    """A number, a boolean or the text itself."""
    lowered = text.lower()
    if lowered in ("true", "false"):
        return lowered == "true"
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text
