"""Analysis 7: threshold comparison (Fowler 2013 Ch. 9 §VII: re-run with a lower
threshold and compare; Table 9.5's "threshold" error of 0.15 arcmin).

The images are detected again at each k-sigma detection threshold (:class:`StarDetector`'s
``sigma``) and solved as they were (:mod:`._rerun`): detections, matches, rms residual, success and
time per threshold, and the mean change of the residual of the stars matched both at that
threshold and in the records.
"""

from __future__ import annotations

from collections.abc import Sequence

from ...errors import InvalidInputError
from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._rerun import draw_per_value, per_value, rerun

INFO = AnalysisInfo(
    name="thresholds",
    title="Threshold comparison",
    description="The images detected again at several k-sigma thresholds and solved as before: success, "
                "detections, matches, rms residual and time per threshold, and the mean change of the "
                "residual of the stars matched at both (Fowler 2013's threshold error). Fowler 2013 Ch. 9 §VII.",
    min_sets=1, max_sets=1, needs_images=True,
    params={"sigmas": (list, [3.0, 4.0, 5.0, 6.0, 8.0], "detection thresholds, in noise units (k of k-sigma)")},
    limits={"sigmas": (1, 20)},
)


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    sigmas = [_sigma(v) for v in params["sigmas"]]
    images = rerun(INFO.name, "sigmas", sets, "sigma", sigmas)
    summary_table = per_value(images, sigmas)
    fig = draw_per_value(summary_table, "detection threshold k (sigma)", INFO.title)
    summary = {f"success rate at {k:g} sigma": rate for k, rate in zip(sigmas, summary_table["success_rate"],
                                                                          strict=True)}
    return AnalysisResult(INFO.name, INFO.title, fig, {"images": images, "thresholds": summary_table}, summary)


def _sigma(value) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not 0.5 <= value <= 1000:
        raise InvalidInputError(f"thresholds: parameter 'sigmas' must hold numbers within 0.5..1000, got {value!r}")
    return float(value)
