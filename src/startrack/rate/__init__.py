"""Angular rate: from attitudes, from matched vectors, filtered, and from streaked images.

Convention: ``omega_rad_s`` is the camera's angular velocity relative to ICRS in camera-frame
components (``rot_cam_from_icrs(t + dt) = exp(-[omega x] dt) rot_cam_from_icrs(t)``); see
:mod:`._estimate`. Modules: :mod:`._from_attitudes` (Samaan 2002 eq. 3), :mod:`._from_vectors` and
:mod:`._frame_match` (frame-to-frame, no catalog), :mod:`._filter` (a constant-rate Kalman
filter), and the streak chain of Sease 2013 chapters 3-4.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import _exports_of, _lazy_exports

if TYPE_CHECKING:  # what mypy and readers see; at run time each name loads on first use (PEP 562)
    from ._catalog_free import catalog_free_rate
    from ._endpoints import (
        DETECTORS,
        CornerDetector,
        EndpointBias,
        calibrate_bias,
        calibrate_bias_model,
        check_detector,
        streak_path,
    )
    from ._estimate import MAX_EXPOSURE_S, MIN_EXPOSURE_S, RateEstimate, axis_error_rad
    from ._filter import FilterState, RateFilter
    from ._frame_match import FrameRate, match_frames, rate_from_frames
    from ._from_attitudes import rate_between, rate_from_attitudes
    from ._from_vectors import rate_from_vectors
    from ._rso import INDICATORS, IndicatorName
    from ._smear_mode import SmearLimits, image_smear_px, usable_for_prediction
    from ._streak_bound import rate_bound, target_chance
    from ._streak_detect import find_streaks
    from ._streak_find import find_streak_candidates
    from ._streak_fit import first_guesses, fit_streaks
    from ._streak_predict import v_mags, zero_point
    from ._streak_rate import (
        METHODS,
        SEGMENT,
        EndpointMethod,
        StreakRate,
        attitudes_from_matches,
        check_endpoint_method,
        choose_mode,
        measure_streaks,
        streak_attitudes,
        streak_rate,
    )
    from ._streak_solve import StreakOptions, StreakSolution, header_exposure_s, solve_streaked
    from ._streak_track import prediction_slack_px, track_streaks

_EXPORTS = _exports_of(__file__)

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
