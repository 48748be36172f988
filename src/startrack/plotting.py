"""matplotlib as an optional dependency: the ``plot`` extra, imported only by the functions that draw.

No startrack module imports matplotlib at import time, so ``import startrack.analysis`` works
without it and never changes a notebook user's backend. A drawing function calls
:func:`new_figure` (or :func:`require_matplotlib` before importing a matplotlib submodule); when
matplotlib is not installed that raises :class:`MissingExtraError`, whose message names the extra
to install. Figures use matplotlib's object API (:class:`matplotlib.figure.Figure`): no pyplot,
no global state, no backend switched.
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING, Any

from .errors import StartrackError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PLOT_EXTRA = "pip install 'startrack[plot]'"
"""The command that installs matplotlib with startrack (the ``plot`` extra of pyproject.toml)."""


class MissingExtraError(StartrackError, ImportError):
    """An optional dependency is not installed; the message names the extra that installs it."""


def require_matplotlib(what: str = "drawing a figure") -> ModuleType:
    """The ``matplotlib`` module, imported now (its pyplot is never imported).

    Parameters
    ----------
    what : str
        What needs matplotlib, for the message ("drawing a figure", "plot_solution").

    Returns
    -------
    module
        The imported ``matplotlib`` package.

    Raises
    ------
    MissingExtraError
        matplotlib is not installed (or is hidden); the message says ``pip install 'startrack[plot]'``.
    """
    try:
        import matplotlib
    except ImportError as exc:
        raise MissingExtraError(f"{what} needs matplotlib, which is not installed: {PLOT_EXTRA}") from exc
    return matplotlib


def new_figure(**kwargs: Any) -> Figure:
    """A new :class:`matplotlib.figure.Figure` (object API, no pyplot, no backend set).

    Parameters
    ----------
    **kwargs
        Passed to ``Figure`` (``figsize`` in inches, ``dpi``, ``layout``, ...).

    Raises
    ------
    MissingExtraError
        matplotlib is not installed; the message names the ``plot`` extra.
    """
    require_matplotlib()
    from matplotlib.figure import Figure

    return Figure(**kwargs)
