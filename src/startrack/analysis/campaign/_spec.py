"""The campaign spec: a TOML file read with :mod:`tomllib`, checked whole before any work.

A spec has the tables ``[campaign]`` (name, level, trials per cell, seed, attitudes, tolerance,
mode), ``[base]`` (scenario parameters of the level; unset ones take their defaults),
``[sweep]`` (a list of values for any parameter; the cells are the product of the lists, the
last axis varying fastest), and optionally ``[budget]`` (mode "budget", :mod:`._budget`) and
``[[reference]]`` (the seed's numbers to print beside ours, :mod:`._reference`). See
``docs/campaigns.md``.
"""

from __future__ import annotations

import itertools
import json
import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...errors import InvalidInputError
from ._params import Param, SpecError
from .levels import Level, get_level

TABLES = ("campaign", "base", "sweep", "budget", "reference")

CAMPAIGN_KEYS: dict[str, Param] = {p.name: p for p in (
    Param("name", "str", None, "a name of letters, digits, '.', '_' and '-'"),
    Param("level", "str", "stars", "what a trial does: stars, image, sequence (docs/campaigns.md)"),
    Param("trials", "int", 100, "trials per cell", lo=1, hi=10_000_000),
    Param("seed", "int", 0, "seed of every trial's random stream", lo=0, hi=2**63 - 1),
    Param("attitudes", "str", "uniform", "uniform on SO(3), or a Fibonacci sky lattice with random roll",
          choices=("uniform", "fibonacci")),
    Param("tolerance_px", "float", 5.0, "a solution is correct within this many pixel angles at the image corner",
          lo=0.01, hi=1000.0),
    Param("mode", "str", "sweep", "sweep: the product of [sweep]; budget: error sources one at a time",
          choices=("sweep", "budget")),
    Param("description", "str", "", "one paragraph for the report"),
)}

_NAME = re.compile(r"^[A-Za-z0-9._-]{1,80}$")


@dataclass(frozen=True)
class Cell:
    """One combination of parameters: every parameter of the level, with its value.

    Attributes
    ----------
    index : int
    params : dict
        Parameter name -> the value the trials use (defaults filled in).
    label : str
        The swept values as ``key=value, ...`` (or the budget source's name).
    source : str or None
        The error source of a budget cell.
    """

    index: int
    params: dict[str, Any]
    label: str
    source: str | None = None


@dataclass(frozen=True)
class CampaignSpec:
    """A checked campaign spec (see the module docstring).

    Attributes
    ----------
    name, level, mode, attitudes, description : str
    trials, seed : int
    tolerance_px : float
    base : dict
        The ``[base]`` values as checked (not the defaults of keys left out).
    sweep : dict
        Axis name -> tuple of checked values, in spec order.
    budget : dict
        The ``[budget]`` table as given (checked by :mod:`._budget`).
    reference : tuple of dict
        The ``[[reference]]`` tables as given.
    text : str
        The TOML text the spec was read from.
    level_obj : Level or None
        The level object (see :attr:`level_def`).
    """

    name: str
    level: str
    trials: int
    seed: int
    attitudes: str = "uniform"
    tolerance_px: float = 5.0
    mode: str = "sweep"
    description: str = ""
    base: dict[str, Any] = field(default_factory=dict)
    sweep: dict[str, tuple[Any, ...]] = field(default_factory=dict)
    budget: dict[str, Any] = field(default_factory=dict)
    reference: tuple[dict[str, Any], ...] = ()
    text: str = ""
    level_obj: Level | None = field(default=None, repr=False, compare=False)

    @property
    def level_def(self) -> Level:
        """The level; the spec carries it, so that a worker process unpickling the spec imports
        the module that defines it (a level registered outside this package works on Dask too)."""
        return self.level_obj if self.level_obj is not None else get_level(self.level)

    @property
    def swept(self) -> list[str]:
        return list(self.sweep)

    def cells(self) -> list[Cell]:
        """The cells, in order (their index is their position)."""
        if self.mode == "budget":
            from ._budget import budget_cells

            return budget_cells(self)
        params = self.level_def.params
        defaults = {name: p.default for name, p in params.items()}
        out = []
        for index, values in enumerate(itertools.product(*self.sweep.values())):
            chosen = dict(zip(self.sweep, values, strict=True))
            label = ", ".join(f"{k}={_show(v)}" for k, v in chosen.items()) or "base"
            out.append(Cell(index, {**defaults, **self.base, **chosen}, label))
        return out

    def as_dict(self) -> dict[str, Any]:
        """The spec as plain JSON-able tables (for the manifest; compared on ``--resume``)."""
        campaign = {"name": self.name, "level": self.level, "trials": self.trials, "seed": self.seed,
                    "attitudes": self.attitudes, "tolerance_px": self.tolerance_px, "mode": self.mode,
                    "description": self.description}
        return json.loads(json.dumps({"campaign": campaign, "base": self.base,
                                      "sweep": {k: list(v) for k, v in self.sweep.items()},
                                      "budget": self.budget, "reference": list(self.reference)}))


def _show(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, tuple):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    return str(value).lower() if isinstance(value, bool) else str(value)


def _table(data: Mapping[str, Any], name: str) -> dict[str, Any]:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise SpecError(f"[{name}] must be a table, got {type(value).__name__}")
    return value


def _campaign_table(data: Mapping[str, Any]) -> dict[str, Any]:
    table = _table(data, "campaign")
    unknown = sorted(set(table) - set(CAMPAIGN_KEYS))
    if unknown:
        raise SpecError(f"[campaign] {unknown[0]}: unknown key; valid: {', '.join(CAMPAIGN_KEYS)}")
    if "name" not in table:
        raise SpecError("[campaign] name: missing; give the campaign a name (letters, digits, '.', '_', '-')")
    out = {key: param.default for key, param in CAMPAIGN_KEYS.items()}
    out.update({key: CAMPAIGN_KEYS[key].check(value, "[campaign]") for key, value in table.items()})
    if not _NAME.match(out["name"]):
        raise SpecError(f"[campaign] name: {out['name']!r} must be 1-80 letters, digits, '.', '_' or '-'")
    return out


def _checked(params: Mapping[str, Param], table: Mapping[str, Any], where: str) -> dict[str, Any]:
    out = {}
    for key, value in table.items():
        if key not in params:
            raise SpecError(f"{where} {key}: unknown parameter of this level; valid: {', '.join(params)}")
        out[key] = params[key].check(value, where)
    return out


def _sweep(params: Mapping[str, Param], table: Mapping[str, Any]) -> dict[str, tuple[Any, ...]]:
    out = {}
    for key, values in table.items():
        if key not in params:
            raise SpecError(f"[sweep] {key}: unknown parameter of this level; valid: {', '.join(params)}")
        if not isinstance(values, list) or not values:
            raise SpecError(f"[sweep] {key}: must be a non-empty list of values, got {values!r}")
        out[key] = tuple(params[key].check(v, "[sweep]") for v in values)
        if len(set(map(_value_key, out[key]))) != len(out[key]):
            raise SpecError(f"[sweep] {key}: repeats a value ({list(values)!r})")
    return out


def _value_key(value: Any) -> str:
    """A sweep value as the cells tell it apart: ``repr``, with -0.0 as 0.0 (the same number,
    and the same cell, as 0.0) in a number or a list of numbers."""
    if isinstance(value, float):
        return repr(value + 0.0)  # -0.0 + 0.0 is 0.0
    if isinstance(value, list | tuple):
        return repr([_value_key(v) for v in value])
    return repr(value)


def _references(data: Mapping[str, Any]) -> tuple[dict[str, Any], ...]:
    refs = data.get("reference", [])
    if isinstance(refs, dict):
        refs = [refs]
    if not isinstance(refs, list) or not all(isinstance(r, dict) for r in refs):
        raise SpecError("[[reference]] must be a list of tables (write each as [[reference]])")
    for i, ref in enumerate(refs):
        for key in ("title", "metric", "rows"):
            if key not in ref:
                raise SpecError(f"[[reference]] {i}: missing key {key!r} (each needs title, metric and rows)")
    return tuple(refs)


def parse_spec(text: str, source: str = "<spec>") -> CampaignSpec:
    """Read and check a spec from TOML text.

    Raises
    ------
    SpecError
        For TOML that does not parse, an unknown table or key, a value of the wrong type or out
        of range, naming the key and what is valid.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{source}: not valid TOML: {exc}") from None
    unknown = sorted(set(data) - set(TABLES))
    if unknown:
        raise SpecError(f"{source}: unknown table [{unknown[0]}]; valid: {', '.join(f'[{t}]' for t in TABLES)}")
    head = _campaign_table(data)
    level = get_level(head["level"])
    spec = CampaignSpec(**head, base=_checked(level.params, _table(data, "base"), "[base]"),
                        sweep=_sweep(level.params, _table(data, "sweep")), budget=_table(data, "budget"),
                        reference=_references(data), text=text, level_obj=level)
    _check_cells(spec)
    return spec


MAX_CELLS = 100_000
"""The most cells a sweep may have: the product of its lists is checked before the cells are made
(a sweep of 10^6 cells took minutes to start and a manifest of hundreds of MB; a campaign of this
size is a sweep to split, or a finer grid than any figure shows)."""


def _check_cells(spec: CampaignSpec) -> None:
    if spec.mode == "sweep" and spec.budget:
        raise SpecError("[budget] is only read with [campaign] mode = \"budget\"")
    sizes = [len(values) for values in spec.sweep.values()]
    if math.prod(sizes) > MAX_CELLS:
        shape = " x ".join(f"{len(v)} {k}" for k, v in spec.sweep.items())
        raise SpecError(f"[sweep] makes {math.prod(sizes):,} cells ({shape}), more than {MAX_CELLS:,}; sweep fewer "
                        "values, or split the campaign")
    cells = spec.cells()
    from ._reference import check_references  # reference reads the spec's cells: imported late

    try:
        check_references(spec.reference, cells)
    except InvalidInputError as exc:
        raise SpecError(str(exc)) from None  # it names the reference already
    check = spec.level_def.check
    if check is None:
        return
    for cell in cells:
        try:
            check(cell.params)
        except SpecError as exc:
            raise SpecError(f"cell {cell.index} ({cell.label}): {exc}") from None


def load_spec(path: str | Path) -> CampaignSpec:
    """Read and check the spec file at ``path`` (see :func:`parse_spec`)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError(f"cannot read the campaign spec {path}: {exc}") from None
    return parse_spec(text, str(path))
