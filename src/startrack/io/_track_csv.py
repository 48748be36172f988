"""Writing a Tracker's per-frame results as CSV (documented columns, one row per frame).

Columns: ``frame, file, t_s, mode, status, ra_deg, dec_deg, roll_deg, qx, qy, qz, qw,
rate_x_deg_s, rate_y_deg_s, rate_z_deg_s, n_matched, residual_px, time_ms, reason``. The
quaternion is ``rot_cam_from_icrs`` with qw >= 0; the rate is the camera's angular velocity in
the camera frame. Empty fields where there is no value. A frame that could not be used (an
unreadable file, another frame size) has mode ``none``, status ``error`` and the problem in
``reason`` (:func:`error_row`).

:func:`track_csv_writer` writes the rows as they come to a temporary file that replaces the
target only when the sequence is done (:func:`startrack.io._atomic.open_output`): an interrupted
run leaves the previous CSV as it was.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ._atomic import open_output

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


ERROR_STATUS = "error"
"""``status`` of a frame that could not be used."""


def error_row(frame: int, file: str, t_s: float, reason: str) -> list[str]:
    """The row of a frame that could not be used: its number, file, time and the problem."""
    row = {"frame": str(frame), "file": file, "t_s": _fmt(t_s, 4), "mode": "none", "status": ERROR_STATUS,
           "n_matched": "0", "reason": " ".join(reason.split())}
    return [row.get(column, "") for column in COLUMNS]


@contextmanager
def track_csv_writer(path: str | os.PathLike, *, inputs: Iterable[str | os.PathLike] = ()
                     ) -> Iterator[Callable[[list[str]], None]]:
    """Yield a function that writes one row; the header is written first, the file replaced at the end."""
    with open_output(path, "w", newline="", inputs=inputs) as fh:
        writer = csv.writer(fh)
        writer.writerow(COLUMNS)

        def write(row: list[str]) -> None:
            writer.writerow(row)
            fh.flush()

        yield write


def write_track_csv(path: str | os.PathLike, rows: Iterable[list[str]], *,
                    inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write the rows (from :func:`track_row`) under the header (:func:`track_csv_writer`)."""
    with track_csv_writer(path, inputs=inputs) as write:
        for row in rows:
            write(row)
    return Path(path)
