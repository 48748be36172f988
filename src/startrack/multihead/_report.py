"""A :class:`RigSolution` as plain JSON values and as a short table (``startrack solve-rig``)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import require
from ..results import AttitudeSolution
from ..rig import CameraRig
from ..units import ARCSEC
from ._solution import RigSolution


def _num(value) -> float | None:
    """A float for JSON, None for NaN, infinite or missing values."""
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _quat(rot) -> dict[str, float]:
    qx, qy, qz, qw = (float(v) for v in rot.as_quat(canonical=True))
    return {"qx": qx, "qy": qy, "qz": qz, "qw": qw}


def _head(solution: RigSolution, name: str, n_stars: int) -> dict[str, Any]:
    own: AttitudeSolution | None = solution.heads.get(name)
    matches = solution.matches.get(name)
    out: dict[str, Any] = {"status": own.status.value if own else "no_match", "reason": own.reason if own else "",
                           "n_stars": int(n_stars), "n_matched": len(matches) if matches is not None else 0,
                           "used": name in solution.heads_used, "inconsistent": name in solution.inconsistent_heads,
                           "centroid_sigma_px": _num(solution.centroid_sigma_px.get(name)),
                           "sigma_cross_arcsec": _num(solution.sigma_cross_arcsec.get(name)),
                           "sigma_roll_arcsec": _num(solution.sigma_roll_arcsec.get(name))}
    if own is not None and own.solved:
        out.update({"ra_deg": _num(own.ra_deg), "dec_deg": _num(own.dec_deg), "roll_deg": _num(own.roll_deg),
                    **_quat(own.rot_cam_from_icrs), "own_sigma_cross_arcsec": _num(own.sigma_cross_boresight_arcsec),
                    "own_sigma_roll_arcsec": _num(own.sigma_roll_arcsec)})
    if matches is not None and len(matches):
        res = solution.residuals_arcsec.get(name, np.full(len(matches), np.nan))
        out["matches"] = [{"index": int(i), "hip": int(h), "residual_arcsec": _num(r)}
                          for i, h, r in zip(matches.det_index, matches.hip, res, strict=True)]
    return out


def rig_solution_to_dict(solution: RigSolution, rig: CameraRig, n_stars: dict[str, int]) -> dict[str, Any]:
    """JSON-ready dictionary of a rig solve (the keys are listed in ``startrack solve-rig --help``)."""
    out: dict[str, Any] = {"status": solution.status.value, "reason": solution.reason}
    if solution.rot_body_from_icrs is not None:
        ra, dec, roll = solution.radec_roll_deg()
        cov = require(solution.covariance_rad2, "the rig solution's covariance")
        sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None)) / ARCSEC
        out.update({**_quat(solution.rot_body_from_icrs), "ra_deg": ra, "dec_deg": dec, "roll_deg": roll,
                    "sigma_body_arcsec": [_num(v) for v in sigma], "consistency_deg": _num(solution.consistency_deg),
                    "mode": solution.mode, "seed_head": solution.seed_head, "heads_used": list(solution.heads_used),
                    "inconsistent_heads": list(solution.inconsistent_heads), "n_matched": solution.n_matched,
                    "false_match_prob": _num(solution.false_match_prob)})
    out["solve_time_s"] = _num(solution.solve_time_s)
    out["heads"] = {h.name: _head(solution, h.name, n_stars.get(h.name, 0)) for h in rig}
    return out


def rig_solution_table(data: dict[str, Any]) -> str:
    """A human-readable table of :func:`rig_solution_to_dict`'s output."""
    rows = [("status", "solved" if data["status"] == "ok" else data["status"])]
    if data["status"] != "ok":
        rows.append(("reason", data["reason"]))
    else:
        rows += [("RA, Dec", f"{data['ra_deg']:.5f} deg, {data['dec_deg']:+.5f} deg (body +z, ICRS)"),
                 ("roll", f"{data['roll_deg']:.4f} deg"),
                 ("identified", f"{data['mode']} (first: {data['seed_head']})"),
                 ("stars", f"{data['n_matched']} matched in heads {', '.join(data['heads_used'])}"),
                 ("1-sigma", "body x, y, z " + ", ".join(_fmt(v) for v in data["sigma_body_arcsec"]) + " arcsec"),
                 ("consistency", f"{_fmt(data['consistency_deg'], 4)} deg" +
                  (f" (inconsistent: {', '.join(data['inconsistent_heads'])})" if data["inconsistent_heads"] else "")),
                 ("qx qy qz qw", " ".join(f"{data[k]:+.9f}" for k in ("qx", "qy", "qz", "qw")))]
    rows.append(("time", f"{data['solve_time_s'] * 1e3:.1f} ms"))
    for name, head in data["heads"].items():
        sigmas = f"cross {_fmt(head['sigma_cross_arcsec'])}, roll {_fmt(head['sigma_roll_arcsec'])} arcsec"
        rows.append((f"head {name}", f"{head['n_matched']} of {head['n_stars']} stars matched, own: "
                                     f"{head['status']}; {sigmas} (joint)"))
    return "\n".join(f"{k:<14}{v}" for k, v in rows)


def _fmt(value, digits: int = 2) -> str:
    return "n/a" if value is None else f"{value:.{digits}f}"
