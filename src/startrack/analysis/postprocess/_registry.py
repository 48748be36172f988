"""The analyses by name, and :func:`run_analysis`, the one entry point of the CLI and the server.

To add an analysis: a module with ``INFO`` (an :class:`~.core.AnalysisInfo`) and
``run(result_sets, params) -> AnalysisResult`` (the sets and parameters already checked), listed
in :data:`_MODULES` (Fowler 2013's "AnalysisFns" registry, Fowler 2013 Ch.8, without the restart).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import Any

from ...errors import InvalidInputError
from . import _compare as compare
from . import _corrections as corrections
from . import _gallery as gallery
from . import _histograms as histograms
from . import _magnitude as magnitude
from . import _radial as radial
from . import _repeatability as repeatability
from . import _sweep as sweep
from . import _thresholds as thresholds
from ._core import AnalysisInfo, AnalysisResult, ResultSet, check_params, check_sets

_MODULES = (histograms, gallery, radial, magnitude, corrections, repeatability, thresholds, compare, sweep)
ANALYSES: Mapping[str, AnalysisInfo] = MappingProxyType({m.INFO.name: m.INFO for m in _MODULES})
"""name -> :class:`AnalysisInfo`, in Fowler 2013 Ch.8's order."""
_RUNNERS: dict[str, Callable[[tuple[ResultSet, ...], dict], AnalysisResult]] = {m.INFO.name: m.run for m in _MODULES}


def get_info(name: str) -> AnalysisInfo:
    """The :class:`AnalysisInfo` of ``name``; InvalidInputError listing the valid names otherwise."""
    if not isinstance(name, str) or name not in ANALYSES:
        raise InvalidInputError(f"unknown analysis {name!r}; valid analyses: {', '.join(ANALYSES)}")
    return ANALYSES[name]


def run_analysis(name: str, result_sets: Sequence[ResultSet], params: Mapping[str, Any] | None = None
                 ) -> AnalysisResult:
    """Run the analysis ``name`` over ``result_sets``.

    Parameters
    ----------
    name : str
        A key of :data:`ANALYSES`.
    result_sets : sequence of ResultSet
        ``min_sets`` to ``max_sets`` of them, none empty.
    params : mapping, optional
        Values for the analysis's parameters (the others take their defaults).

    Returns
    -------
    AnalysisResult
        The figure, its tables and a summary.

    Raises
    ------
    InvalidInputError
        An unknown analysis (listing the valid ones), a wrong number of sets, an unknown
        parameter, a value of the wrong type or out of range, or a record without pixels for an
        analysis that needs them; the message names the problem.
    """
    info = get_info(name)
    sets = check_sets(info, result_sets)
    checked = check_params(info, params)
    if info.needs_images:
        for s in sets:
            for record in s.records:
                if record.image is None and record.path is None:
                    raise InvalidInputError(f"{name} needs the images' pixels; record {record.name!r} of set "
                                            f"{s.name!r} has no image and no path")
    return _RUNNERS[name](sets, checked)
