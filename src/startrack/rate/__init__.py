"""Angular rate: from attitudes, from matched vectors, filtered, and from streaked images.

Convention: ``omega_rad_s`` is the camera's angular velocity relative to ICRS in camera-frame
components (``rot_cam_from_icrs(t + dt) = exp(-[omega x] dt) rot_cam_from_icrs(t)``); see
:mod:`.estimate`. Modules: :mod:`.from_attitudes` (seed 004 eq. 3), :mod:`.from_vectors`
(frame-to-frame, no catalog), :mod:`.filter` (a constant-rate Kalman filter), and the streak
chain of seed 001 chapters 3-4.
"""

from __future__ import annotations

from .. import _lazy_exports

_EXPORTS = {  # name -> the module that defines it, imported on first use (PEP 562)
    "RateEstimate": ".estimate",
    "axis_error_rad": ".estimate",
    "FilterState": ".filter",
    "RateFilter": ".filter",
    "rate_between": ".from_attitudes",
    "rate_from_attitudes": ".from_attitudes",
    "match_frames": ".from_vectors",
    "rate_from_vectors": ".from_vectors",
}

__all__ = [
    "FilterState",
    "RateEstimate",
    "RateFilter",
    "axis_error_rad",
    "match_frames",
    "rate_between",
    "rate_from_attitudes",
    "rate_from_vectors",
]

__getattr__, __dir__ = _lazy_exports(__name__, _EXPORTS)
