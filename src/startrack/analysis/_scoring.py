"""Judging solves against truth the same way for every method, and summarising them.

A solve is a *success* when the returned attitude is within ``tolerance`` of the truth; a *false
solve* when a solution is returned but lies outside it; otherwise a *failure* (no solution). The
error of an attitude is split into its cross-boresight part and its roll (the components of the
rotation vector of ``truth * estimate.inv()`` across and along the camera's z axis), and the roll
is weighted by ``roll_weight``, the image's half-diagonal over the focal length, which turns it
into the motion it causes at the image corner: ``sqrt(cross**2 + (roll_weight * roll)**2)``.
With ``roll_weight = 1`` this is the total error angle (DESIGN.md §3), never smaller. The default
tolerance is 5 pixel angles (5 / focal length in px): centroid noise of 0.1-0.5 px moves the
image by well under a pixel, while a wrong identification is off by degrees. (The total error
angle alone counted as false 2 of 100 correct identifications of a narrow field with few stars
whose roll, 140-170 arcsec off, moved the image corners by 0.3 px.)
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..camera import Camera
from ..frames import (
    angle_between,
    boresight,
    radec_roll_from_rotation,
    rotation_from_radec_roll,
)
from ..units import ARCSEC

TOLERANCE_PIXELS: float = 5.0


def tolerance_rad(camera: Camera, pixels: float = TOLERANCE_PIXELS) -> float:
    """``pixels`` pixel angles at the principal point, in radians."""
    return pixels / math.sqrt(camera.fx * camera.fy)


def attitude_errors_rad(truths: list[Rotation], estimates: list[Rotation | None],
                        roll_weight: float = 1.0) -> NDArray[np.float64]:
    """Attitude error (rad) of each estimate, its roll weighted (see the module docstring); NaN
    where there is none; shape (N,)."""
    out = np.full(len(truths), np.nan)
    for i, (truth, est) in enumerate(zip(truths, estimates, strict=True)):
        if est is not None:
            cross_x, cross_y, roll = (truth * est.inv()).as_rotvec()
            out[i] = math.sqrt(cross_x**2 + cross_y**2 + (roll_weight * roll) ** 2)
    return out


def roll_weight(camera: Camera) -> float:
    """Half-diagonal of the image over the focal length: roll (rad) to motion at the corner (rad)."""
    return math.hypot(camera.width / 2 / camera.fx, camera.height / 2 / camera.fy)


def rotations_from_radec_roll_deg(ra_deg, dec_deg, roll_deg) -> list[Rotation | None]:
    """Attitudes from RA, Dec, roll in degrees (tetra3's output); None where any is NaN."""
    out: list[Rotation | None] = []
    for ra, dec, roll in zip(ra_deg, dec_deg, roll_deg, strict=True):
        finite = np.isfinite(ra) and np.isfinite(dec) and np.isfinite(roll)
        out.append(rotation_from_radec_roll(*np.radians([ra, dec, roll])) if finite else None)
    return out


def boresight_and_roll_errors(truths: list[Rotation], ra_deg, dec_deg,
                              roll_deg) -> dict[str, NDArray]:
    """Boresight error and signed roll difference (both rad, NaN when unsolved), shapes (N,).

    Compares a peer's reported RA / Dec / roll with the truth in our RA / Dec / roll format, to
    check that the two roll definitions agree.
    """
    ests = rotations_from_radec_roll_deg(ra_deg, dec_deg, roll_deg)
    bore = np.full(len(truths), np.nan)
    droll = np.full(len(truths), np.nan)
    for i, (truth, est) in enumerate(zip(truths, ests, strict=True)):
        if est is None:
            continue
        bore[i] = float(angle_between(boresight(truth), boresight(est)))
        true_roll = float(radec_roll_from_rotation(truth)[2])
        droll[i] = (math.radians(roll_deg[i]) - true_roll + math.pi) % (2 * math.pi) - math.pi
    return {"boresight_err_rad": bore, "roll_diff_rad": droll}


def summarize(solved: NDArray[np.bool_], err_rad: NDArray[np.float64], time_s: NDArray[np.float64],
              tol_rad: float) -> dict[str, float]:
    """Success rate, false-solve rate, median and 95th-percentile time (ms) of one run.

    Times are over all trials, solved or not (the time to get an answer, including giving up).
    """
    solved = np.asarray(solved, dtype=bool)
    err = np.asarray(err_rad, dtype=float)
    good = solved & (err <= tol_rad)
    n = max(int(solved.size), 1)
    t_ms = np.asarray(time_s, dtype=float) * 1e3
    return {
        "n": int(solved.size),
        "success_rate": float(good.sum() / n),
        "false_rate": float((solved & ~good).sum() / n),
        "median_ms": float(np.median(t_ms)) if t_ms.size else float("nan"),
        "p95_ms": float(np.percentile(t_ms, 95)) if t_ms.size else float("nan"),
        "median_err_arcsec": float(np.median(err[good]) / ARCSEC) if good.any() else float("nan"),
    }
