"""``startrack solve IMAGE [IMAGE ...]`` and ``startrack solve FOLDER``: the batch of
:mod:`startrack.cli._batch` for lost-in-space solving (one record per image: the image's path
and :func:`startrack.io._solution_json.solution_to_dict` of its solution, or an error)."""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import Any

from ..errors import require
from ._batch import BatchSpec, Record

HEADER = "{image}  status           RA deg    Dec deg   roll deg  FOV deg  matched   rms\"  time ms  reason"

CSV_COLUMNS = ("image", "status", "reason", "ra_deg", "dec_deg", "constellation", "roll_deg", "fov_deg", "focal_px",
               "mirrored", "n_matched", "n_detections", "guided_stars", "residual_rms_arcsec",
               "sigma_cross_boresight_arcsec", "sigma_roll_arcsec", "false_match_prob", "solve_time_s",
               "qx", "qy", "qz", "qw")
"""Columns of ``startrack solve --csv`` (one row per image; empty where not solved)."""


def solve_record(path: Path, *, solver_options: dict[str, Any], channel: str | None) -> Record:
    """Read, detect and solve one image: ``{"image": path, **solution_to_dict(...)}``.

    Raises the reader's and the solver's errors (ImageReadError, InvalidInputError) for the
    batch to report on the image's line.
    """
    from ..io import read_image, solution_to_dict
    from ..solve import solve_image
    from ._solve_cmd import explain_blank

    image = read_image(path, channel=channel)
    solution = solve_image(image, **solver_options)
    detections = require(solution.detections, "the image solve's detections")
    solution = explain_blank(solution, detections, image)
    return {"image": str(path), **solution_to_dict(solution, detections)}


def _number(value: float | None, spec: str, width: int) -> str:
    return "-".rjust(width) if value is None or not math.isfinite(value) else format(value, spec).rjust(width)


def solve_line(record: Record, width: int) -> str:
    """One table line (the columns of :data:`HEADER`)."""
    solved = record["status"] == "ok"
    status = "solved" if solved else record["status"]
    matched = len(record["matches"]) if solved else "-"
    stars = f"{matched}/{record['n_detections']}" if "n_detections" in record else "-"
    time_ms = record.get("solve_time_s")
    cells = [record["image"].ljust(width), status.ljust(13),
             _number(record.get("ra_deg"), ".5f", 10), _number(record.get("dec_deg"), "+.5f", 10),
             _number(record.get("roll_deg"), ".4f", 10), _number(record.get("fov_deg"), ".4f", 8),
             stars.rjust(8), _number(record.get("residual_rms_arcsec"), ".2f", 6),
             _number(None if time_ms is None else 1e3 * time_ms, ".1f", 8)]
    text = "  ".join(cells[:2]) + " ".join(cells[2:])
    return f"{text}  {record['reason']}" if record["reason"] else text


def solve_csv_rows(record: Record) -> list[Record]:
    """The CSV row of a record (:data:`CSV_COLUMNS`)."""
    n_matched = len(record["matches"]) if "matches" in record else None
    return [{**record, "n_matched": n_matched}]


def solve_spec(solver_options: dict[str, Any], channel: str | None) -> BatchSpec:
    """The batch of ``startrack solve`` with these (checked) solver options."""
    return BatchSpec(name="solve",
                     process=functools.partial(solve_record, solver_options=solver_options, channel=channel),
                     header=HEADER, line=solve_line, csv_columns=CSV_COLUMNS, csv_rows=solve_csv_rows,
                     done_statuses=frozenset({"ok"}))
