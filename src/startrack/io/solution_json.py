"""Serialising results to plain JSON-ready dictionaries (documented keys, stable order).

Quaternions are written as named columns ``qx, qy, qz, qw`` (scalar last); angles carry their
unit in the key; pixel positions are in our 0-based convention. Undefined numbers (NaN, inf) are
written as None (JSON null), so the output is standard JSON.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..results import AttitudeSolution, Detections


def _num(value: float | None) -> float | None:
    return None if value is None or not math.isfinite(float(value)) else float(value)


def solution_to_dict(solution: AttitudeSolution, detections: Detections | None = None) -> dict[str, Any]:
    """A JSON-ready dictionary of a solve: status, attitude, uncertainty, matches, timing."""
    out: dict[str, Any] = {"status": solution.status.value, "reason": solution.reason}
    if solution.rot_cam_from_icrs is not None:
        qx, qy, qz, qw = (float(q) for q in solution.quaternion_xyzw)
        out.update({
            "ra_deg": _num(solution.ra_deg), "dec_deg": _num(solution.dec_deg),
            "roll_deg": _num(solution.roll_deg), "fov_deg": _num(solution.fov_deg),
            "qx": qx, "qy": qy, "qz": qz, "qw": qw,
            "focal_px": _num(solution.camera.fx) if solution.camera else None,
            "sigma_cross_boresight_arcsec": _num(solution.sigma_cross_boresight_arcsec),
            "sigma_roll_arcsec": _num(solution.sigma_roll_arcsec),
            "residual_rms_arcsec": _num(float(np.sqrt(np.mean(solution.residuals_arcsec**2)))),
            "false_match_prob": _num(solution.false_match_prob),
            "matches": _matches(solution, detections),
        })
    out["solve_time_s"] = _num(solution.solve_time_s)
    if detections is not None:
        out["n_detections"] = len(detections)
    return out


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
