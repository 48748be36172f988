"""What the ground-photo analyses share: the site parameters, the true attitude of a record, and
an attitude error split into pointing and roll.

The error of an estimate against a reference attitude is the rotation ``estimate * reference^-1``
expressed in the camera frame (Fowler 2013 eq. 7.15 with the missing inverse, Fowler 2013 Ch.7 §III.B; the form of
:mod:`startrack.calibrate._repeatability`): its rotation vector's length is the total error, the
length of its (x, y) part the pointing error (the boresight's) and its z part the roll error.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from ...calibrate import Site, get_site
from ...errors import InvalidInputError
from ...units import ARCSEC
from .._records import ImageRecord

SITE_PARAMS: dict[str, tuple[type, Any, str]] = {
    "site": (str, None, "a saved or built-in site name (startrack.calibrate._sites); default the records' site"),
    "latitude_deg": (float, None, "site latitude, north positive (with longitude_deg, instead of site)"),
    "longitude_deg": (float, None, "site longitude, east positive"),
    "height_m": (float, 0.0, "site height above sea level, m"),
}
SITE_LIMITS: dict[str, tuple[float | None, float | None]] = {
    "latitude_deg": (-90.0, 90.0), "longitude_deg": (-180.0, 360.0), "height_m": (-500.0, 9000.0)}


def site_from_params(analysis: str, params: Mapping[str, Any], records: Sequence[ImageRecord]) -> Site | None:
    """The site the parameters name (``site`` or ``latitude_deg`` + ``longitude_deg``), else the
    first record's ``site``, else None."""
    if params.get("site"):
        if params.get("latitude_deg") is not None or params.get("longitude_deg") is not None:
            raise InvalidInputError(f"{analysis}: give 'site' or 'latitude_deg' and 'longitude_deg', not both")
        return get_site(params["site"])
    lat, lon = params.get("latitude_deg"), params.get("longitude_deg")
    if (lat is None) != (lon is None):
        raise InvalidInputError(f"{analysis}: give both 'latitude_deg' and 'longitude_deg' (or 'site')")
    if lat is not None and lon is not None:
        return Site("parameters", float(lat), float(lon), float(params.get("height_m") or 0.0))
    return next((r.site for r in records if r.site is not None), None)


def true_rotation(record: ImageRecord) -> Rotation | None:
    """The record's true ``rot_cam_from_icrs``: its simulator truth, else the one read from its file."""
    if record.truth is not None:
        return record.truth.rot_cam_from_icrs
    return record.true_rot_cam_from_icrs


def error_arcsec(estimate: Rotation, reference: Rotation) -> tuple[float, float, float]:
    """Total, pointing and signed roll error (arcsec) of ``estimate`` against ``reference``
    (module docstring)."""
    rotvec = (estimate * reference.inv()).as_rotvec()
    return (float(np.linalg.norm(rotvec) / ARCSEC), float(np.hypot(rotvec[0], rotvec[1]) / ARCSEC),
            float(rotvec[2] / ARCSEC))
