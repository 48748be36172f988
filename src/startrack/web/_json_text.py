"""JSON text from a client, read strictly: the request bodies and form fields of the API.

Python's ``json`` module takes more than JSON and more than the checks after it can hold:

* ``NaN``, ``Infinity`` and ``-Infinity`` are not JSON (RFC 8259); they are refused here, so that
  no NaN reaches a job's files (whose JSON writer refuses it, after the job's folder exists).
* A whole number of any length is a Python int, which overflows where a check compares it with a
  float (``math.isfinite(10**400)`` raises). A number of more than :data:`MAX_INT_DIGITS` digits
  is read as a float instead (``inf`` beyond the float range), which the checks then refuse as
  "not a finite number" or "not a whole number", naming the field.
* Nesting deep enough to exhaust Python's recursion (``[[[[...]]]]``, 30,000 deep) is refused.

Every refusal is a ValueError, which the callers already turn into 400 or 422.
"""

from __future__ import annotations

import json
from typing import Any

MAX_INT_DIGITS = 19
"""Whole numbers of up to this many digits (int64's range, every seed and size) stay ints."""


def _int(text: str) -> int | float:
    return int(text) if len(text.lstrip("-")) <= MAX_INT_DIGITS else float(text)


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number (use null, or leave the key out)")


def loads(text: str | bytes) -> Any:
    """``json.loads(text)`` with the rules of the module docstring.

    Raises
    ------
    ValueError
        Not JSON: malformed, a NaN / Infinity constant, or nested too deeply.
    """
    try:
        return json.loads(text, parse_int=_int, parse_constant=_no_constant)
    except RecursionError:
        raise ValueError("nested too deeply") from None
