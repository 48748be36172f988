"""Analysis: scoring against the truth, star lists and scenes for benchmarks, plots, star counts,
the records of solved images; Monte Carlo campaigns (:mod:`.campaign`) and post-processing
analyses over result sets (:mod:`.postprocess`), each a subpackage with its own public names.

Modules
-------
scoring            attitude errors against the truth, tolerances, summaries
starlists          simulated star lists (conditions, sky, generation) for the matcher benchmarks
streak_scenes      streaked scenes (stars and a turning satellite) for the rate tests and benchmarks
rso_passes         satellite passes of the seed tables
availability       stars in the field over random pointings
plots              solution and star-count figures (matplotlib ``Figure``, object API)
calibration_plots  distortion, residual and repeatability figures
records            :class:`ImageRecord`, one solved image as the analyses read it

The names are imported on first use (PEP 562), so ``import startrack.analysis`` loads neither
matplotlib nor the campaign's Dask.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._availability import star_counts
    from ._calibration_plots import plot_distortion, plot_repeatability, plot_residuals
    from ._plots import display_stretch, plot_solution, plot_star_counts, solution_title
    from ._records import ImageRecord
    from ._rso_passes import elements
    from ._scoring import (
        TOLERANCE_PIXELS,
        attitude_errors_rad,
        boresight_and_roll_errors,
        roll_weight,
        rotations_from_radec_roll_deg,
        summarize,
        tolerance_rad,
    )
    from ._starlists import Conditions, StarList, generate_star_lists, load_sky, make_star_list
    from ._streak_scenes import (
        StreakScene,
        paths_apart,
        render_streak_scene,
        spin_rate,
        star_field,
        star_paths,
        streak_sensor,
        turning_rso_snapshot,
    )

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
