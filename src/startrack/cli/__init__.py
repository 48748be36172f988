"""The ``startrack`` command line: one module per subcommand, each with ``main(argv) -> int``
(dispatched by :func:`startrack.cli.main.main`, the console script).

The public interface of this package is the command line itself: :data:`SUBCOMMANDS` names
each subcommand, the module that runs it and its one-line help. See ``startrack --help`` and
``startrack <cmd> --help``.
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "SUBCOMMANDS": ".main",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
