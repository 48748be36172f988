"""The ``startrack`` command line: one module per subcommand, each with ``main(argv) -> int``
(dispatched by :func:`main`, the console script; ``python -m startrack`` runs the same).

The public interface of this package is the command line itself: :func:`main` runs it (an
``argv`` list in, the exit status out), :data:`SUBCOMMANDS` names each subcommand, the module
that runs it and its one-line help. See ``startrack --help`` and ``startrack <cmd> --help``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._main import SUBCOMMANDS, main

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
