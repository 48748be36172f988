"""Attitude profiles in files: a CSV of ``t_s, qx, qy, qz, qw`` (``rot_cam_from_icrs``, scalar last)."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ._motion import AttitudeProfile, RecordedProfile, _times


def load_profile(path: str | os.PathLike) -> RecordedProfile:
    """A recorded profile from a CSV file with columns ``t_s, qx, qy, qz, qw``.

    The quaternion is that of ``rot_cam_from_icrs``, scalar last (see docs/conventions.md);
    other columns are ignored.

    Raises
    ------
    InvalidInputError
        If the file is missing, lacks a column, or holds a non-number.
    """
    path = Path(path)
    try:
        with open(path, newline="") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as exc:
        raise InvalidInputError(f"cannot read attitude profile {path}: {exc.strerror}") from None
    columns = ("t_s", "qx", "qy", "qz", "qw")
    if not rows or any(c not in rows[0] for c in columns):
        raise InvalidInputError(f"attitude profile {path} needs a header with columns {', '.join(columns)}")
    try:
        data = np.array([[float(row[c]) for c in columns] for row in rows])
    except (TypeError, ValueError):
        raise InvalidInputError(f"attitude profile {path} holds a value that is not a number") from None
    if not np.all(np.isfinite(data)) or np.any(np.linalg.norm(data[:, 1:], axis=1) == 0):
        raise InvalidInputError(f"attitude profile {path} holds NaN, inf or a zero quaternion")
    return RecordedProfile(data[:, 0], Rotation.from_quat(data[:, 1:]))


def save_profile(path: str | os.PathLike, profile: AttitudeProfile, times_s: ArrayLike) -> Path:
    """Write ``profile`` sampled at ``times_s`` as a CSV readable by :func:`load_profile`."""
    t = _times(times_s)
    quats = profile.attitudes(t).as_quat()
    path = Path(path)
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["t_s", "qx", "qy", "qz", "qw"])
        writer.writerows([f"{ti:.9f}", *(f"{q:+.15f}" for q in qi)] for ti, qi in zip(t, quats, strict=True))
    return path
