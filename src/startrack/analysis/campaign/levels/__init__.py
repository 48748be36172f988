"""Campaign levels: what one trial does, and the parameters it takes.

A :class:`Level` has its parameters (:class:`~startrack.analysis.campaign._params.Param`), the
extra columns its rows add to :data:`~startrack.analysis.campaign._outcome.COLUMNS`, ``run``, one
trial: ``run(params, attitude, rng, tolerance_px) -> TrialOutput``, and optionally ``check``, which
refuses a cell's combination of parameters before any work (``SpecError``). A worker is warmed
for a cell by running one throwaway trial of it (:func:`warm`), which loads the catalog and the
pattern database and compiles exactly the kernels the trials use. ``chunk_trials`` is the default
number of trials sent to a worker at once (about a second of work). ``warm_key(params)``, when
given, says which cells need the same warm-up (e.g. leaving out a parameter that only picks a
frame): one throwaway trial is run per distinct key instead of per distinct cell.

Built-in levels: ``stars`` (:mod:`._stars`), ``image`` (:mod:`._image`), ``sequence``
(:mod:`._sequence`), and every other module of this package whose name does not start with an
underscore and is not a helper (:data:`HELPERS`): the module ``name.py`` defines level ``name``
and registers it on import. Code elsewhere registers more with :func:`register`.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from .._params import Param, SpecError

__all__ = ["HELPERS", "WARM_ROTATION", "Level", "TrialOutput", "get_level", "level_names", "register", "warm"]


@dataclass(frozen=True)
class TrialOutput:
    """One trial's row (every column but cell, trial and the swept values), and optionally its
    frame (the image, for ``campaign rerun --save-image``)."""

    row: dict[str, Any]
    image: np.ndarray | None = None
    truth: Any = None


@dataclass(frozen=True)
class Level:
    """A kind of trial (see the module docstring)."""

    name: str
    doc: str
    params: Mapping[str, Param]
    run: Callable[[Mapping[str, Any], Rotation, np.random.Generator, float], TrialOutput]
    columns: Mapping[str, pa.DataType] = field(default_factory=dict)
    check: Callable[[Mapping[str, Any]], None] | None = None
    chunk_trials: int = 20
    warm_key: Callable[[Mapping[str, Any]], Any] | None = None


WARM_ROTATION = Rotation.from_euler("zyx", [40.0, 20.0, 10.0], degrees=True)
"""The attitude of the throwaway trial that warms a worker (any attitude with stars will do)."""


def warm(level: Level, params: Mapping[str, Any]) -> None:
    """Run one throwaway trial of ``params``, so that what it loads and compiles is paid once."""
    level.run(params, WARM_ROTATION, np.random.default_rng(0), 5.0)


_LEVELS: dict[str, Level] = {}
HELPERS = frozenset({"common", "scene"})
"""Modules of this package that hold shared parameters and builders, not a level."""


def _builtin() -> list[str]:
    """The built-in levels: each is the module ``_<level name>`` of this package (private like
    every implementation module; the level's name is its public handle)."""
    names = (m.name[1:] for m in pkgutil.iter_modules(__path__) if m.name.startswith("_"))
    return [name for name in names if name and not name.startswith("_") and name not in HELPERS]


def register(level: Level) -> Level:
    """Add a level (its name must be new)."""
    if level.name in _LEVELS and _LEVELS[level.name] is not level:
        raise ValueError(f"campaign level {level.name!r} is already registered")
    _LEVELS[level.name] = level
    return level


def level_names() -> list[str]:
    """Names of the built-in and registered levels."""
    return sorted(set(_builtin()) | set(_LEVELS))


def get_level(name: str) -> Level:
    """The level called ``name`` (importing a built-in one on first use).

    Raises
    ------
    SpecError
        For an unknown name, listing the valid ones.
    """
    if name not in _LEVELS and name in _builtin():
        importlib.import_module(f"._{name}", __name__)
    if name not in _LEVELS:
        raise SpecError(f"[campaign] level: unknown level {name!r}; valid: {', '.join(level_names())}")
    return _LEVELS[name]
