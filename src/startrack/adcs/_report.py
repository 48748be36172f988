"""A run's summary as a dict (the ``--json`` object), as a text table, and its files.

Summary keys: ``feedback``, ``law``, ``plant``, ``duration_s``, ``wall_time_s``, ``overall`` and
``steps`` (each with ``steady_state_error_deg``, ``overshoot_pct``, ``rise_time_s``,
``settling_time_s``, ``avg_power_w``, ``peak_power_w``; steps add ``t_start_s``, ``target_q2``,
``complete``), ``meets_table_5_3``, ``seed`` (the seed's Table 5.3 bounds and powers),
``plans`` (count, infeasible count, mean SLSQP time) and, with the star tracker,
``tracker`` (frames, tracked, median and 95th-percentile latency, median processing time,
attitude and rate errors about y, warm-up time).
"""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path

import numpy as np

from ._loop import RECORDED, RunRecord
from ._metrics import METRIC_KEYS, SEED_POWER_W, SEED_TABLE_5_3, StepMetrics
from ._star_tracker_feedback import FrameRecord, fit_noise_model

ARCSEC_PER_RAD = 180.0 / math.pi * 3600.0


def summary(record: RunRecord, steps: list[StepMetrics], overall: StepMetrics) -> dict:
    """The JSON-ready summary of a run (NaN as None)."""
    c = record.config
    plans = record.plans
    out = {"feedback": c.feedback, "law": c.law, "plant": c.plant, "duration_s": c.scenario.duration_s,
           "wall_time_s": record.wall_s, "overall": overall.to_dict(), "steps": [s.to_dict() for s in steps],
           "meets_table_5_3": overall.meets_table_5_3(), "seed": {**SEED_TABLE_5_3, **SEED_POWER_W},
           "plans": {"count": len(plans), "infeasible": sum(p.status == "infeasible" for p in plans),
                     "mean_slsqp_s": float(np.mean([p.wall_s for p in plans])) if plans else None}}
    if record.frames:
        out["tracker"] = tracker_summary(record)
    return out


def tracker_summary(record: RunRecord) -> dict:
    """Frame counts, latency and the errors about y of the tracker's frames."""
    frames: list[FrameRecord] = record.frames
    ok = [f for f in frames if f.ok]
    lat = np.array([f.latency_s for f in ok]) if ok else np.array([math.nan])
    out = {"frames": len(frames), "tracked": len(ok),
           "latency_median_s": float(np.median(lat)), "latency_p95_s": float(np.percentile(lat, 95)),
           "processing_median_s": float(np.median([f.processing_s for f in ok])) if ok else None}
    if len(ok) >= 2:
        model = fit_noise_model(frames, record.t_s, record.omega_true)
        out.update(theta_error_rms_arcsec=math.hypot(model.theta_bias_rad, model.theta_sigma_rad) * ARCSEC_PER_RAD,
                   rate_error_sigma_arcsec_s=model.rate_sigma_rad_s * ARCSEC_PER_RAD)
    return _clean(out)


def _clean(data: dict) -> dict:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in data.items()}


def _fmt(value: float | None, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def table(data: dict) -> str:
    """Per-step and overall metrics as text, with the seed's bounds."""
    head = f"{'step':<8}{'t0 s':>7}{'q2':>7}{'ss err deg':>12}{'overshoot %':>13}{'rise s':>9}" \
           f"{'settle s':>10}{'avg W':>10}{'peak W':>9}"
    digits = dict(zip(METRIC_KEYS, (4, 2, 2, 2, 4, 3), strict=True))
    lines = [head]
    rows = [(str(k + 1), s) for k, s in enumerate(data["steps"])] + [("overall", data["overall"])]
    for label, row in rows:
        cells = "".join(f"{_fmt(row[key], digits[key]):>{w}}" for key, w in zip(METRIC_KEYS, (12, 13, 9, 10, 10, 9),
                                                                               strict=True))
        t0 = _fmt(row.get("t_start_s"), 0)
        q2 = _fmt(row.get("target_q2"), 2)
        lines.append(f"{label:<8}{t0:>7}{q2:>7}{cells}")
    s = data["seed"]
    lines.append(f"{'seed':<8}{'':>14}{'< ' + str(s['steady_state_error_deg']):>12}{'< ' + str(s['overshoot_pct']):>13}"
                 f"{'< ' + str(s['rise_time_s']):>9}{'< ' + str(s['settling_time_s']):>10}"
                 f"{'~' + str(s['avg_power_w']):>10}{'~' + str(s['peak_power_w']):>9}")
    return "\n".join(lines)


def write_files(record: RunRecord, data: dict, out_dir: str | os.PathLike) -> list[Path]:
    """``run.csv`` (every tick), ``frames.csv`` and ``tracker_noise.json`` (star tracker only) and
    ``summary.json``; returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "run.csv", out / "summary.json"]
    columns = np.column_stack([record.t_s] + [record.series[name] for name in RECORDED])
    np.savetxt(paths[0], columns, delimiter=",", header=",".join(("t_s", *RECORDED)), comments="", fmt="%.9g")
    paths[1].write_text(json.dumps(data, indent=2, allow_nan=False) + "\n")
    if record.frames:
        paths.append(out / "frames.csv")
        _write_frames(record.frames, paths[-1])
        if sum(f.ok for f in record.frames) >= 2:
            paths.append(out / "tracker_noise.json")
            model = fit_noise_model(record.frames, record.t_s, record.omega_true)
            paths[-1].write_text(json.dumps(model.to_dict(), indent=2) + "\n")
    return paths


def _write_frames(frames: list[FrameRecord], path: Path) -> None:
    names = list(FrameRecord.__dataclass_fields__)
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(names)
        for f in frames:
            writer.writerow([getattr(f, n) for n in names])
