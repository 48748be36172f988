"""Analysis 9: a parameter sweep over one detection setting (StellarSolver's tester table of
settings against results; issue 16 item 4).

``setting`` names a :class:`~startrack.detect.StarDetector` field with a number, boolean or
string value; each of ``values`` replaces it in the records' own detector, and the images are
detected and solved again (:mod:`._rerun`, the engine of the threshold comparison): success,
matches, rms residual and time per value.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import fields

from ...detect import StarDetector
from ...errors import InvalidInputError
from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._rerun import draw_per_value, per_value, rerun

SWEEPABLE = tuple(f.name for f in fields(StarDetector)
                  if f.name not in ("dark_frame", "dark_columns", "smear_px", "channel", "max_block_px"))
"""Settings with a single number, boolean or string value."""

def check(params: dict) -> None:
    """Each value once, and each of the setting's kind (text, true / false, or a number, as its
    default): the sweep of ``kernel`` with the default values 3.0 .. 6.0 is refused when it is
    asked for. Whether a value of the right kind is valid depends on the record's detector
    (:func:`._rerun.detectors_for` says so when the analysis runs)."""
    setting, values = params["setting"], list(params["values"])
    default = getattr(StarDetector(), setting)
    typed = [_typed(setting, v) for v in values]  # as the sweep runs them: 4 and 4.0 are one sigma
    if len({repr(v + 0.0) if isinstance(v, float) else repr(v) for v in typed}) != len(typed):  # -0.0 is 0.0
        raise InvalidInputError(f"sweep: parameter 'values' holds a value twice: {values!r}")
    for value in values:
        if not _same_kind(default, value):
            raise InvalidInputError(f"sweep: parameter 'values': {value!r} is not a value of {setting} "
                                    f"(of the kind of its default, {default!r})")


def _same_kind(default, value) -> bool:
    """Text for text, true / false for true / false, a number for a number (or None)."""
    if isinstance(default, bool) or isinstance(value, bool):
        return isinstance(default, bool) and isinstance(value, bool)
    if default is None:
        return True
    if isinstance(default, str):
        return isinstance(value, str)
    return isinstance(value, int | float)


INFO = AnalysisInfo(
    name="sweep",
    title="Parameter sweep over a detection setting",
    description="A grid over one detector setting: each value replaces the setting in the images' own "
                "detector, and the images are detected and solved again, giving success, matches, rms "
                "residual and time per value.",
    min_sets=1, max_sets=1, needs_images=True,
    params={"setting": (str, "sigma", "the StarDetector setting to vary"),
            "values": (list, [3.0, 4.0, 5.0, 6.0], "its values")},
    limits={"values": (1, 30)},
    choices={"setting": SWEEPABLE},
    check=check,
)


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    setting = params["setting"]
    values = [_typed(setting, v) for v in params["values"]]
    images = rerun(INFO.name, "values", sets, setting, values)
    table = per_value(images, values)
    fig = draw_per_value(table, setting, f"{INFO.title}: {setting}")
    summary = {f"success rate at {setting}={v}": rate for v, rate in zip(values, table["success_rate"], strict=True)}
    return AnalysisResult(INFO.name, INFO.title, fig, {"images": images, "values": table}, summary)


def _typed(setting: str, value):
    """A float setting takes whole numbers as floats (``sigma=4``); an int one refuses 4.5."""
    default = getattr(StarDetector(), setting)
    if isinstance(default, float) and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if isinstance(default, int) and not isinstance(default, bool) and isinstance(value, float) and value.is_integer():
        return int(value)
    return value
