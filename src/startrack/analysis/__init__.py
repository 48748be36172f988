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

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "star_counts": ".availability",
    "plot_distortion": ".calibration_plots",
    "plot_repeatability": ".calibration_plots",
    "plot_residuals": ".calibration_plots",
    "display_stretch": ".plots",
    "plot_solution": ".plots",
    "plot_star_counts": ".plots",
    "ImageRecord": ".records",
    "elements": ".rso_passes",
    "TOLERANCE_PIXELS": ".scoring",
    "attitude_errors_rad": ".scoring",
    "boresight_and_roll_errors": ".scoring",
    "roll_weight": ".scoring",
    "rotations_from_radec_roll_deg": ".scoring",
    "summarize": ".scoring",
    "tolerance_rad": ".scoring",
    "Conditions": ".starlists",
    "StarList": ".starlists",
    "generate_star_lists": ".starlists",
    "load_sky": ".starlists",
    "make_star_list": ".starlists",
    "StreakScene": ".streak_scenes",
    "paths_apart": ".streak_scenes",
    "render_streak_scene": ".streak_scenes",
    "spin_rate": ".streak_scenes",
    "star_field": ".streak_scenes",
    "star_paths": ".streak_scenes",
    "streak_sensor": ".streak_scenes",
    "turning_rso_snapshot": ".streak_scenes",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
