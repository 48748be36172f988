"""Serialising results to plain JSON-ready dictionaries (documented keys, stable order).

Quaternions are written as named columns ``qx, qy, qz, qw`` (scalar last); angles carry their
unit in the key; pixel positions are in our 0-based convention. Undefined numbers (NaN, inf) are
written as None (JSON null), so the output is standard JSON.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..catalog import constellation_of
from ..errors import require
from ..results import AttitudeSolution, Detections


def _num(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(float(value)) else float(value)


def solution_to_dict(solution: AttitudeSolution, detections: Detections | None = None) -> dict[str, Any]:
    """A JSON-ready dictionary of a solve: status, attitude, uncertainty, matches, timing."""
    out: dict[str, Any] = {"status": solution.status.value, "reason": solution.reason}
    if solution.rot_cam_from_icrs is not None:
        qx, qy, qz, qw = (float(q) for q in require(solution.quaternion_xyzw, "the solution's quaternion"))
        out.update({
            "ra_deg": _num(solution.ra_deg), "dec_deg": _num(solution.dec_deg),
            "constellation": constellation_of(solution.ra_deg, solution.dec_deg),
            "roll_deg": _num(solution.roll_deg), "fov_deg": _num(solution.fov_deg),
            "qx": qx, "qy": qy, "qz": qz, "qw": qw,
            "focal_px": _num(solution.camera.fx) if solution.camera else None,
            "pixel_scale_arcsec": _num(solution.camera.pixel_scale_arcsec) if solution.camera else None,
            "mirrored": bool(solution.camera.mirrored) if solution.camera else None,
            "sigma_cross_boresight_arcsec": _num(solution.sigma_cross_boresight_arcsec),
            "sigma_roll_arcsec": _num(solution.sigma_roll_arcsec),
            "residual_rms_arcsec": _num(float(np.sqrt(np.mean(solution.residuals_arcsec**2)))),
            "false_match_prob": _num(solution.false_match_prob),
            "guided_stars": int(solution.guided_stars),
            "epoch_jyear": _num(solution.epoch_jyear), "epoch_source": solution.epoch_source or None,
            "fov_source": solution.fov_source or None,
            "matches": _matches(solution, detections),
        })
    out["solve_time_s"] = _num(solution.solve_time_s)
    if detections is not None:
        out["n_detections"] = len(detections)
    return {**out, **streak_fields(solution)}


def streak_fields(solution: AttitudeSolution) -> dict:
    """What a solve from streaks (:class:`startrack.rate._streak_solve.StreakSolution`) adds to the
    output (empty for point stars): ``mode`` "streak", the mid-exposure time the attitude refers
    to (``t_mid_s``, s after the exposure starts; and
    ``time_mid_utc`` when the header dates it), ``exposure_s``, the fitted rate (camera frame,
    deg/s: the turn during the exposure, ``turn_deg``, over the exposure; None without one),
    whether it is trusted (``rate_status``, ``rate_reason``) and whether its sign is known
    (``time_order_known``)."""
    if type(solution) is AttitudeSolution:  # a point solve: the streak module need not be imported
        return {}
    from ..rate import StreakSolution

    if not isinstance(solution, StreakSolution) or solution.mode != "streak":
        return {}
    rate = solution.rate
    exposure = _num(solution.exposure_s)
    time_mid = solution.time_mid
    return {"mode": "streak", "t_mid_s": _num(solution.t_mid_s), "exposure_s": exposure,
            "time_mid_utc": _utc_isot(time_mid),
            "rate_status": rate.status.value, "rate_reason": rate.reason,
            "time_order_known": bool(solution.time_order_known),
            "rate_deg_s": _nums(np.degrees(solution.turn_rad) / exposure) if exposure else None,
            "turn_deg": _nums(np.degrees(solution.turn_rad))}


def _utc_isot(time: object | None) -> str | None:
    """The ISO UTC time of an astropy Time (what a streak solution's ``time_mid`` holds when the
    header dates the frame), else None. astropy is imported only when there is one (then it is
    already)."""
    if time is None:
        return None
    from astropy.time import Time

    return time.utc.isot if isinstance(time, Time) else None


def _nums(values) -> list[float | None]:
    return [_num(float(v)) for v in values]


def _matches(solution: AttitudeSolution, detections: Detections | None) -> list[dict[str, Any]]:
    rows = []
    for k, (i, hip) in enumerate(zip(solution.matches.det_index, solution.matches.hip, strict=True)):
        row: dict[str, Any] = {"index": int(i), "hip": int(hip), "residual_arcsec": _num(solution.residuals_arcsec[k])}
        if detections is not None:
            row.update({"x": float(detections.x[i]), "y": float(detections.y[i])})
        rows.append(row)
    return rows


def detections_to_dict(detections: Detections) -> dict[str, Any]:
    """A JSON-ready dictionary of detections (brightest first)."""
    keys = ("x", "y", "flux", "sigma_px", "area_px", "peak", "elongation")
    return {"background": float(detections.background), "noise": float(detections.noise),
            "stars": [{k: float(getattr(detections, k)[i]) for k in keys} for i in range(len(detections))]}
