"""The columns every trial row has, and how a solution fills them.

The schema is ``docs/campaigns.md``'s table: the solver's status, whether it is *correct* (within
``tolerance_px`` pixel angles at the image corner, the roll weighted by the half-diagonal over
the focal length, as :mod:`startrack.analysis._scoring` judges the lost-in-space benchmarks), the
signed error components, the solver's own 1-sigma, counts, time and the true boresight.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pyarrow as pa
from scipy.spatial.transform import Rotation

from ...camera import Camera
from ...frames import radec_roll_from_rotation
from ...results import AttitudeSolution
from ...units import ARCSEC
from .._scoring import roll_weight, tolerance_rad

COLUMNS: dict[str, pa.DataType] = {
    "cell": pa.int32(), "trial": pa.int32(),
    "status": pa.string(), "error": pa.string(), "solved": pa.bool_(), "correct": pa.bool_(),
    "err_x_arcsec": pa.float64(), "err_y_arcsec": pa.float64(), "err_roll_arcsec": pa.float64(),
    "err_cross_arcsec": pa.float64(), "err_total_arcsec": pa.float64(),
    "sigma_cross_arcsec": pa.float64(), "sigma_roll_arcsec": pa.float64(),
    "n_stars": pa.int32(), "n_matched": pa.int32(), "false_match_prob": pa.float64(), "time_s": pa.float64(),
    "ra_deg": pa.float64(), "dec_deg": pa.float64(), "roll_deg": pa.float64(),
}
"""Name and Arrow type of the columns of every level (after ``cell``, ``trial`` come the swept
parameters, then these; a level appends its own)."""

NAN = float("nan")


def truth_columns(rot_cam_from_icrs: Rotation | None) -> dict[str, float]:
    """The true boresight RA, Dec and roll (deg) of a trial (NaN when unknown)."""
    if rot_cam_from_icrs is None:
        return {"ra_deg": NAN, "dec_deg": NAN, "roll_deg": NAN}
    ra, dec, roll = radec_roll_from_rotation(rot_cam_from_icrs)
    return {"ra_deg": math.degrees(ra), "dec_deg": math.degrees(dec), "roll_deg": math.degrees(roll)}


def error_columns(truth: Rotation, estimate: Rotation | None, camera: Camera,
                  tolerance_px: float) -> dict[str, Any]:
    """Signed error components (arcsec, camera frame) of ``estimate`` and whether it is correct.

    The components are those of the rotation vector of ``truth * estimate.inv()`` (x, y across
    the boresight, z the roll); ``camera`` (the true one) sets the tolerance and the roll weight.
    """
    if estimate is None:
        return {"correct": False, "err_x_arcsec": NAN, "err_y_arcsec": NAN, "err_roll_arcsec": NAN,
                "err_cross_arcsec": NAN, "err_total_arcsec": NAN}
    ex, ey, ez = (truth * estimate.inv()).as_rotvec()
    weighted = math.sqrt(ex * ex + ey * ey + (roll_weight(camera) * ez) ** 2)
    return {"correct": bool(weighted <= tolerance_rad(camera, tolerance_px)),
            "err_x_arcsec": ex / ARCSEC, "err_y_arcsec": ey / ARCSEC, "err_roll_arcsec": ez / ARCSEC,
            "err_cross_arcsec": math.hypot(ex, ey) / ARCSEC,
            "err_total_arcsec": math.sqrt(ex * ex + ey * ey + ez * ez) / ARCSEC}


def solution_columns(solution: AttitudeSolution, truth: Rotation, camera: Camera, tolerance_px: float,
                     n_stars: int) -> dict[str, Any]:
    """The common columns of a trial that ended in ``solution`` (solved or not)."""
    row = {"status": solution.status.name, "error": "", "solved": solution.solved,
           "sigma_cross_arcsec": solution.sigma_cross_boresight_arcsec if solution.solved else NAN,
           "sigma_roll_arcsec": solution.sigma_roll_arcsec if solution.solved else NAN,
           "n_stars": int(n_stars), "n_matched": len(solution.matches) if solution.solved else 0,
           "false_match_prob": float(solution.false_match_prob), "time_s": float(solution.solve_time_s)}
    row.update(error_columns(truth, solution.rot_cam_from_icrs if solution.solved else None, camera, tolerance_px))
    row.update(truth_columns(truth))
    return row


def failure_columns(status: str, error: str, truth: Rotation | None) -> dict[str, Any]:
    """The common columns of a trial that raised (``status`` "ERROR") or whose worker died ("LOST")."""
    row = {"status": status, "error": error, "solved": False, "correct": False, "sigma_cross_arcsec": NAN,
           "sigma_roll_arcsec": NAN, "n_stars": 0, "n_matched": 0, "false_match_prob": 1.0, "time_s": NAN,
           "err_x_arcsec": NAN, "err_y_arcsec": NAN, "err_roll_arcsec": NAN, "err_cross_arcsec": NAN,
           "err_total_arcsec": NAN}
    row.update(truth_columns(truth))
    return row


def empty_value(kind: pa.DataType) -> Any:
    """What a failure row holds in a level's own column of this type (NaN, 0, False or "")."""
    if pa.types.is_floating(kind):
        return NAN
    if pa.types.is_integer(kind):
        return 0
    if pa.types.is_boolean(kind):
        return False
    return ""


def arrow_type(kind: str) -> pa.DataType:
    """The Arrow type of a swept parameter of :data:`startrack.analysis.campaign._params.KINDS` kind."""
    return {"float": pa.float64(), "int": pa.int64(), "bool": pa.bool_(),
            "str": pa.string(), "floats": pa.list_(pa.float64())}[kind]


def as_column_value(value: Any) -> Any:
    """A parameter value as stored in a column (None, "auto", stays None; tuples become lists)."""
    if isinstance(value, tuple):
        return list(value)
    if isinstance(value, np.generic):
        return value.item()
    return value
