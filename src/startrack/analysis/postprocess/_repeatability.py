"""Analysis 6: fixed-mount repeatability of a folder of ground photos (Fowler 2013 Ch. 7 §III.B and
Ch. 9 §VI; Table 9.5's "truth" column).

The solved images that have a time are handed to
:func:`startrack.calibrate._repeatability.repeatability` with the site: the mean mounting rotation
(camera from east-north-up), its standard error (eq. 9.1), and each image's total, pointing and
roll error against it, in arcmin as the thesis gives them (Aptina 1.5 +- 0.6' total).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from astropy.time import Time

from ...calibrate import altaz_from_vectors, repeatability
from ...errors import InvalidInputError, require
from ...units import ARCMIN
from ._core import AnalysisInfo, AnalysisResult, ResultSet
from ._figures import draw_repeatability, new_figure
from ._ground import SITE_LIMITS, SITE_PARAMS, site_from_params

INFO = AnalysisInfo(
    name="repeatability",
    title="Fixed-mount repeatability",
    description="For images from a camera fixed to the ground: the mean mounting rotation (camera from "
                "east-north-up), its standard error, and each image's total, pointing and roll error "
                "against it over time, in arcmin. Needs each image's time and the site. Fowler 2013 Ch. 7 "
                "§III.B, Ch. 9 §VI.",
    min_sets=1, max_sets=1,
    params=dict(SITE_PARAMS),
    limits=SITE_LIMITS,
)


def run(sets: Sequence[ResultSet], params: dict) -> AnalysisResult:
    """The analysis of this module over result sets and parameters already checked by
    :func:`~.registry.run_analysis` (see :data:`INFO` and the module docstring)."""
    records = sets[0].records
    site = site_from_params(INFO.name, params, records)
    if site is None:
        raise InvalidInputError("repeatability: give parameter 'site' (a site name) or 'latitude_deg' and "
                                "'longitude_deg'; the records carry no site")
    usable = sorted((r for r in records if r.solution.solved and r.time is not None),
                    key=lambda r: require(r.time, "the image time").utc.jd)
    if len(usable) < 2:
        no_time = sum(1 for r in records if r.solution.solved and r.time is None)
        raise InvalidInputError(f"repeatability needs at least two solved images with a time; set {sets[0].name!r} "
                                f"has {len(usable)} ({no_time} solved without a time: give the images a DATE-OBS or "
                                "EXIF time)")
    times = Time([require(r.time, "the image time").utc.isot for r in usable], format="isot", scale="utc")
    result = repeatability(times, [r.solution.rot_cam_from_icrs for r in usable], site)
    fig, axes = new_figure(1, 2, width_in=5.2, height_in=3.8, title=INFO.title)
    draw_repeatability(axes[0, 0], result)
    axes[0, 1].hist(result.total_rad / ARCMIN, bins=max(5, min(30, len(usable) // 2)), color="tab:blue")
    axes[0, 1].set_xlabel("total error, arcmin")
    axes[0, 1].set_ylabel("images")
    minutes = (result.times - result.times[0]).to_value("min")
    images = {"record": [r.name for r in usable], "time_utc": [t.isot for t in result.times],
              "minutes": list(minutes), "total_arcmin": list(result.total_rad / ARCMIN),
              "pointing_arcmin": list(result.pointing_rad / ARCMIN), "roll_arcmin": list(result.roll_rad / ARCMIN)}
    return AnalysisResult(INFO.name, INFO.title, fig, {"images": images, "mount": _mount_table(result, site)},
                          _summary(result, site, len(records) - len(usable)))


def _mount_table(result, site) -> dict[str, list]:
    qx, qy, qz, qw = result.mount.as_quat(canonical=True)
    alt, az = altaz_from_vectors(result.mount.inv().apply([0.0, 0.0, 1.0]))
    return {"qx": [qx], "qy": [qy], "qz": [qz], "qw": [qw],
            "boresight_altitude_deg": [math.degrees(float(alt))], "boresight_azimuth_deg": [math.degrees(float(az))],
            "mount_standard_error_arcmin": [result.mount_standard_error_rad / ARCMIN], "site": [site.name],
            "latitude_deg": [site.latitude_deg], "longitude_deg": [site.longitude_deg]}


def _summary(result, site, left_out: int) -> dict[str, float | int | str]:
    stats = result.summary_arcmin()
    qx, qy, qz, qw = result.mount.as_quat(canonical=True)
    out: dict[str, float | int | str] = {
        "images": int(len(result.total_rad)), "left out (unsolved or no time)": left_out, "site": site.name,
        "mount qx qy qz qw": " ".join(f"{v:+.9f}" for v in (qx, qy, qz, qw)),
        "mount standard error, arcmin": result.mount_standard_error_rad / ARCMIN}
    for name, (mean, sd) in stats.items():
        out[f"{name} error mean, arcmin"] = mean
        out[f"{name} error sd, arcmin"] = sd
    out["time span, min"] = float(np.ptp((result.times - result.times[0]).to_value("min")))
    return out
