"""startrack: an open star-tracker system.

From photons on a detector to a spacecraft's attitude and rate, and from a photo of the night sky
to where the camera pointed. See ``docs/conventions.md`` for the pixel, frame and rotation
conventions every function keeps.

The public names are imported on first use (PEP 562 module ``__getattr__``), so ``import
startrack`` costs a few milliseconds and a command loads only what it calls; ``from startrack
import solve_image`` works as before. Subpackages do the same through :func:`_lazy_exports`.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any

__version__ = "0.1.0"


def _lazy_exports(package: str, exports: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of a package whose names load on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    exports : mapping of str to str
        Public name -> the module (relative to ``package``, e.g. ``".solve"``) that defines it.

    Returns
    -------
    (__getattr__, __dir__)
        ``__getattr__(name)`` imports the module of an exported name, binds the name in the
        package (later look-ups cost nothing) and returns it; any other name is tried as a
        submodule (``startrack.catalog.cone`` after ``import startrack.catalog``, as when the
        package imported it eagerly), else AttributeError.
    """

    def __getattr__(name: str) -> Any:
        origin = exports.get(name)
        if origin is not None:
            value = getattr(importlib.import_module(origin, package), name)
        elif name.startswith("__"):
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        else:
            value = _submodule(package, name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted({*vars(sys.modules[package]), *exports})

    return __getattr__, __dir__


def _submodule(package: str, name: str) -> Any:
    """The submodule ``package.name``, or AttributeError when there is none."""
    try:
        return importlib.import_module(f"{package}.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{package}.{name}":
            raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}") from None


_EXPORTS = {
    "AttitudeSolution": ".results",
    "Camera": ".camera",
    "CameraRig": ".rig",
    "Detections": ".results",
    "RigHead": ".rig",
    "RigSolution": ".multihead",
    "StarMatches": ".results",
    "Status": ".results",
    "get_preset": ".camera",
    "solve_image": ".solve",
    "solve_rig": ".multihead",
    "solve_stars": ".solve",
}

__all__ = sorted([*_EXPORTS, "__version__"])

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
