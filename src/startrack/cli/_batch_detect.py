"""``startrack detect IMAGE [IMAGE ...]`` and ``startrack detect FOLDER``: the batch of
:mod:`startrack.cli._batch` for detection (one record per image: the ``--json`` object of a
single image, with ``status`` "ok" and the time, or an error)."""

from __future__ import annotations

import functools
import time
from pathlib import Path

from ._batch import BatchSpec, Record

HEADER = "{image}  status  stars    width x height  background      noise  threshold  time ms  reason"

STAR_COLUMNS = ("x", "y", "flux", "sigma_px", "mag", "peak_snr", "area_px", "elongation")
CSV_COLUMNS = ("image", "star", *STAR_COLUMNS)
"""Columns of ``startrack detect --csv``: one row per star (brightest first, ``star`` counts from 0);
an image with no star or an error has no row (the table and the summary name it)."""


def detect_record(path: Path, *, detector) -> Record:
    """Detect the stars of one image: the single-image ``--json`` object with ``status`` "ok",
    ``reason`` "", ``n_stars`` and ``detect_time_s`` (s). Raises the reader's errors."""
    from ..io import read_image
    from ._detect_cmd import json_record

    image = read_image(path)
    t0 = time.perf_counter()
    details = detector.detect_details(image)
    elapsed = time.perf_counter() - t0
    return {"image": str(path), "status": "ok", "reason": "", "n_stars": len(details.detections),
            "detect_time_s": elapsed, **json_record(path, details, detector)}


def detect_line(record: Record, width: int) -> str:
    """One table line (the columns of :data:`HEADER`)."""
    name = record["image"].ljust(width)
    if record["status"] != "ok":
        return f"{name}  {record['status']:<6}  {'-':>5}  {'-':>16}  {'-':>10} {'-':>10}  {'-':>9}  {'-':>7}  " \
               f"{record['reason']}"
    size = f"{record['width']} x {record['height']}"
    return (f"{name}  {'ok':<6}  {record['n_stars']:>5}  {size:>16}  {record['background']:10.2f} "
            f"{record['noise']:10.3f}  {record['k_sigma']:9.2f}  {1e3 * record['detect_time_s']:7.1f}")


def detect_csv_rows(record: Record) -> list[Record]:
    """One CSV row per star of a record (:data:`CSV_COLUMNS`)."""
    return [{"image": record["image"], "star": k, **star} for k, star in enumerate(record.get("stars", []))]


def detect_spec(detector) -> BatchSpec:
    """The batch of ``startrack detect`` with this :class:`startrack.detect.StarDetector`."""
    return BatchSpec(name="detect", process=functools.partial(detect_record, detector=detector), header=HEADER,
                     line=detect_line, csv_columns=CSV_COLUMNS, csv_rows=detect_csv_rows,
                     done_statuses=frozenset({"ok"}))
