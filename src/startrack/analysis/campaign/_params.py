"""Scenario parameters of a campaign: their types, ranges, defaults and documentation.

Every key of a spec's ``[base]`` and ``[sweep]`` tables is a :class:`Param` of the campaign's
level; :meth:`Param.check` turns a TOML value into the value a trial uses, or raises
:class:`SpecError` naming the key and what would be valid. ``docs/campaigns.md`` lists them all
(generated from :func:`param_table`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from ...errors import InvalidInputError


class SpecError(InvalidInputError):
    """A campaign spec that cannot be run: the message names the key and what is valid."""


KINDS = ("float", "int", "bool", "str", "floats")
"""Parameter kinds: a number, a whole number, true / false, a string (often from ``choices``) and
a fixed-length list of numbers (``floats``). An ``optional`` parameter also takes "auto" (stored
as None: the library's own choice, e.g. the sensor preset's value)."""


@dataclass(frozen=True)
class Param:
    """One scenario parameter.

    Attributes
    ----------
    name : str
        The key in the spec (unit-suffixed where it has a unit: ``fov_deg``, ``exposure_s``).
    kind : str
        One of :data:`KINDS`.
    default : Any
        The value a trial uses when the spec leaves the key out.
    doc : str
        One line for ``docs/campaigns.md`` and error messages.
    lo, hi : float, optional
        Inclusive bounds of a number (of every element of a ``floats`` list).
    choices : tuple of str, optional
        The valid strings of a ``str`` parameter.
    length : int, optional
        The length of a ``floats`` list.
    optional : bool
        Whether "auto" (None) is valid; an optional parameter's default is usually "auto".
    """

    name: str
    kind: str
    default: Any
    doc: str
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] | None = None
    length: int | None = None
    optional: bool = False

    def check(self, value: Any, where: str) -> Any:
        """The value a trial uses for ``value`` given in table ``where`` (e.g. "[base]").

        Raises
        ------
        SpecError
            Naming ``where``, the key, what was given and what is valid.
        """
        if self.optional and (value is None or value == "auto"):
            return None
        try:
            return _CHECKS[self.kind](self, value)
        except (TypeError, ValueError) as exc:
            raise SpecError(f"{where} {self.name}: {exc} (got {value!r}; {self.doc})") from None

    def valid(self) -> str:
        """What values are valid, in words."""
        if self.choices is not None:
            text = "one of " + ", ".join(repr(c) for c in self.choices)
        else:
            span = _span(self)
            text = {"float": f"a number{span}", "int": f"a whole number{span}", "bool": "true or false",
                    "str": "a string", "floats": f"a list of {self.length} numbers{span}"}[self.kind]
        return text + (' or "auto"' if self.optional else "")


def _span(param: Param) -> str:
    if param.lo is None and param.hi is None:
        return ""
    lo = "-inf" if param.lo is None else f"{param.lo:g}"
    hi = "inf" if param.hi is None else f"{param.hi:g}"
    return f" in [{lo}, {hi}]"


def _within(param: Param, value: int | float) -> None:
    """Refuse a value outside the parameter's bounds (compared in the value's own type)."""
    if (param.lo is not None and value < param.lo) or (param.hi is not None and value > param.hi):
        raise ValueError(f"must be {param.valid()}")


def _number(param: Param, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"must be {param.valid()}")
    out = float(value)
    if not math.isfinite(out):
        raise ValueError(f"must be {param.valid()}")
    _within(param, out)
    return out


def _check_int(param: Param, value: Any) -> int:
    """A whole number within the bounds, compared as integers (through a float, 2**63 - 1 rounds
    up to 2**63 and the largest valid seed was refused)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"must be {param.valid()}")
    _within(param, value)
    return int(value)


def _check_bool(param: Param, value: Any) -> bool:
    if not isinstance(value, bool):
        raise TypeError("must be true or false")
    return value


def _check_str(param: Param, value: Any) -> str:
    if not isinstance(value, str) or (param.choices is not None and value not in param.choices):
        raise ValueError(f"must be {param.valid()}")
    return value


def _check_floats(param: Param, value: Any) -> tuple[float, ...]:
    if not isinstance(value, list | tuple) or len(value) != param.length:
        raise TypeError(f"must be {param.valid()}")
    return tuple(_number(param, v) for v in value)


_CHECKS = {"float": _number, "int": _check_int, "bool": _check_bool, "str": _check_str, "floats": _check_floats}


def params_by_name(*groups: Sequence[Param]) -> dict[str, Param]:
    """One mapping name -> Param from groups of parameters (a later group may not redefine a name)."""
    out: dict[str, Param] = {}
    for group in groups:
        for param in group:
            if param.name in out:
                raise ValueError(f"parameter {param.name!r} is defined twice")
            out[param.name] = param
    return out


def param_table(params: Mapping[str, Param]) -> list[tuple[str, str, str, str]]:
    """(name, valid values, default, doc) rows, for documentation and ``campaign list --params``."""
    return [(p.name, p.valid(), "auto" if p.default is None else repr(p.default), p.doc) for p in params.values()]
