"""Writing a Tracker's per-frame results as CSV (documented columns, one row per frame).

Columns: ``frame, file, t_s, mode, status, ra_deg, dec_deg, roll_deg, qx, qy, qz, qw,
rate_x_deg_s, rate_y_deg_s, rate_z_deg_s, n_matched, residual_px, time_ms, reason``. The
quaternion is ``rot_cam_from_icrs`` with qw >= 0; the rate is the camera's angular velocity in
the camera frame. Empty fields where there is no value.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from .atomic import atomic_path

COLUMNS = ("frame", "file", "t_s", "mode", "status", "ra_deg", "dec_deg", "roll_deg", "qx", "qy", "qz", "qw",
           "rate_x_deg_s", "rate_y_deg_s", "rate_z_deg_s", "n_matched", "residual_px", "time_ms", "reason")


def _fmt(value: float, digits: int = 7) -> str:
    return "" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def track_row(frame: int, file: str, step) -> list[str]:
    """One CSV row of a :class:`startrack.track.TrackStep`."""
    ra, dec, roll = step.radec_roll_deg
    quat = step.rot_cam_from_icrs.as_quat(canonical=True) if step.rot_cam_from_icrs is not None else [math.nan] * 4
    rate = np.degrees(step.rate_rad_s) if step.rate_rad_s is not None else [math.nan] * 3
    return [str(frame), file, _fmt(step.t_s, 4), step.mode, step.status.value, _fmt(ra), _fmt(dec), _fmt(roll),
            *(_fmt(q, 9) for q in quat), *(_fmt(r, 5) for r in rate), str(step.n_matched),
            _fmt(step.residual_rms_px, 3), _fmt(step.time_s * 1e3, 3), step.reason]


def write_track_csv(path: str | os.PathLike, rows: Iterable[list[str]]) -> Path:
    """Write the rows (from :func:`track_row`) under the header, atomically."""
    with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(COLUMNS)
        writer.writerows(rows)
    return Path(path)
