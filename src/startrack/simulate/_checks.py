"""Argument checks shared by the simulator's settings classes (raise InvalidInputError)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidInputError, as_float_array


def positive(name: str, value: float, *, allow_zero: bool = False) -> float:
    """``value`` as a float, if finite and > 0 (or >= 0 with ``allow_zero``); else raise."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{name} must be a number, got {value!r}") from None
    ok = math.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise InvalidInputError(f"{name} must be finite and {bound}, got {value!r}")
    return v


def fraction(name: str, value: float) -> float:
    """``value`` as a float in (0, 1]; else raise."""
    v = positive(name, value)
    if v > 1.0:
        raise InvalidInputError(f"{name} must be a fraction in (0, 1], got {value!r}")
    return v


def finite_array(name: str, value: ArrayLike,
                 shape: tuple[int | None, ...]) -> NDArray[np.float64]:
    """``value`` as a finite float64 array of the given shape (None = any length); else raise."""
    arr = as_float_array(value, name)
    wrong = arr.ndim != len(shape) or any(
        s is not None and s != n for s, n in zip(shape, arr.shape, strict=True))
    if wrong:
        want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise InvalidInputError(f"{name} must have shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"{name} must be finite (got NaN or inf)")
    return arr


def finite_nonnegative(arr: NDArray[np.float64]) -> bool:
    """True if every element is finite and >= 0 (two reductions, no temporary arrays)."""
    return arr.size == 0 or bool(arr.min() >= 0 and np.isfinite(arr.max()))
