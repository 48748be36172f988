"""startrack: an open star-tracker system.

From photons on a detector to a spacecraft's attitude and rate, and from a photo of the night sky
to where the camera pointed. See ``docs/conventions.md`` for the pixel, frame and rotation
conventions every function keeps.

The public names are imported on first use (PEP 562 module ``__getattr__``), so ``import
startrack`` costs a few milliseconds and a command loads only what it calls; ``from startrack
import solve_image`` works as before. Subpackages do the same through :func:`_lazy_exports`.
"""

from __future__ import annotations

import ast
import importlib
import sys
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

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
        submodule (``startrack.catalog._cone`` after ``import startrack.catalog``, as when the
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


def _exports_of(init_file: str) -> dict[str, str]:
    """Public name -> defining module of a lazy package, read from its ``__init__.py``.

    A lazy package lists its names once, as the imports of its ``if TYPE_CHECKING:`` block (what
    mypy and a reader see); at run time nothing there is imported, and this map tells
    :func:`_lazy_exports` which module to load for a name.

    Parameters
    ----------
    init_file : str
        The package's ``__file__``.

    Returns
    -------
    dict of str to str
        Name -> the module relative to the package (``"._solve"``), in the block's order.
    """
    with open(init_file, encoding="utf-8") as file:
        tree = ast.parse(file.read(), init_file)
    exports = {}
    for node in tree.body:
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            for statement in node.body:
                if isinstance(statement, ast.ImportFrom) and statement.level == 1:
                    module = "." + (statement.module or "")
                    exports.update({alias.asname or alias.name: module for alias in statement.names})
    return exports


def _submodule(package: str, name: str) -> Any:
    """The submodule ``package.name``, or AttributeError when there is none."""
    try:
        return importlib.import_module(f"{package}.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{package}.{name}":
            raise
        raise AttributeError(f"module {package!r} has no attribute {name!r}") from None


if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from .camera import Camera, get_preset
    from .multihead import RigSolution, solve_rig
    from .results import AttitudeSolution, Detections, StarMatches, Status
    from .rig import CameraRig, RigHead
    from .solve import solve_image, solve_stars

_EXPORTS = _exports_of(__file__)

__all__ = sorted([*_EXPORTS, "__version__"])

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
