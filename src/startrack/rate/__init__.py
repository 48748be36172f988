"""Angular rate: from attitudes, from matched vectors, filtered, and from streaked images.

Convention: ``omega_rad_s`` is the camera's angular velocity relative to ICRS in camera-frame
components (``rot_cam_from_icrs(t + dt) = exp(-[omega x] dt) rot_cam_from_icrs(t)``); see
:mod:`.estimate`. Modules: :mod:`.from_attitudes` (Samaan 2002 eq. 3), :mod:`.from_vectors`
(frame-to-frame, no catalog), :mod:`.filter` (a constant-rate Kalman filter), and the streak
chain of Sease 2013 chapters 3-4.
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "catalog_free_rate": ".catalog_free",
    "DETECTORS": ".endpoints",
    "EndpointBias": ".endpoints",
    "calibrate_bias": ".endpoints",
    "calibrate_bias_model": ".endpoints",
    "streak_path": ".endpoints",
    "RateEstimate": ".estimate",
    "axis_error_rad": ".estimate",
    "FilterState": ".filter",
    "RateFilter": ".filter",
    "rate_between": ".from_attitudes",
    "rate_from_attitudes": ".from_attitudes",
    "match_frames": ".from_vectors",
    "rate_from_vectors": ".from_vectors",
    "INDICATORS": ".rso",
    "SmearLimits": ".smear_mode",
    "image_smear_px": ".smear_mode",
    "usable_for_prediction": ".smear_mode",
    "find_streaks": ".streak_detect",
    "find_streak_candidates": ".streak_find",
    "first_guesses": ".streak_fit",
    "fit_streaks": ".streak_fit",
    "v_mags": ".streak_predict",
    "zero_point": ".streak_predict",
    "METHODS": ".streak_rate",
    "SEGMENT": ".streak_rate",
    "StreakRate": ".streak_rate",
    "attitudes_from_matches": ".streak_rate",
    "choose_mode": ".streak_rate",
    "measure_streaks": ".streak_rate",
    "streak_attitudes": ".streak_rate",
    "StreakOptions": ".streak_solve",
    "StreakSolution": ".streak_solve",
    "header_exposure_s": ".streak_solve",
    "solve_streaked": ".streak_solve",
    "prediction_slack_px": ".streak_track",
    "track_streaks": ".streak_track",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
