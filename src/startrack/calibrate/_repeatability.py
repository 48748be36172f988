"""Repeatability of a fixed ground mount (Fowler 2013 Ch. 7 §III.B and Ch. 9 §VI, with errata 2 and 4 resolved).

With the camera fixed to the ground, its attitude relative to the local horizon is constant; the
sky turns. For images i at times t_i with solved attitudes ``rot_cam_from_icrs_i``:

1. ``rot_cam_from_enu_i = rot_cam_from_icrs_i * rot_enu_from_icrs(t_i)^-1`` (eq. 7.17);
2. the **mounting** rotation is their average (Markley et al. 2007, the eigenvector average, eq.
   7.18; ``scipy.spatial.transform.Rotation.mean``);
3. each image's "truth" is ``mount * rot_enu_from_icrs(t_i)`` (eq. 7.19);
4. its **error** is the rotation from truth to estimate expressed in the camera frame,
   ``rot_est * rot_truth^-1`` (eq. 7.15 with the missing inverse), split into **pointing** (the
   boresight's angular error, sqrt(dx^2 + dy^2) of the rotation vector) and **roll** (|dz|);
5. the **mounting standard error** (eq. 9.1): per axis, the standard deviation of the individual
   mounting rotations about the mean (small-angle rotation-vector components, in place of the
   thesis's unstated Euler sequence) over sqrt(n); the RMS of the three.

Errors constant in the camera frame (a principal-point bias) are absorbed into the mount; errors
that change with sidereal time (neglected precession, wrong timestamps) show as drift.
The **error budget** (Table 9.5) adds the mount's standard error, the detection threshold's effect,
the lens calibration's 1-sigma (converted to angle) and Bennett's refraction accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from astropy.time import Time
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from ..errors import InvalidInputError
from ..units import ARCMIN
from ._ground import rotation_enu_from_icrs
from ._refraction import BENNETT_ACCURACY_RAD
from ._sites import Site


@dataclass(frozen=True)
class Repeatability:
    """Result of :func:`repeatability`; angles in radians, arrays of shape (n,).

    Attributes
    ----------
    mount : Rotation
        The mean ``rot_cam_from_enu``.
    mount_standard_error_rad : float
    total_rad, pointing_rad, roll_rad : ndarray
        Each image's error against the mount.
    times : Time
    """

    mount: Rotation
    mount_standard_error_rad: float
    total_rad: NDArray[np.float64]
    pointing_rad: NDArray[np.float64]
    roll_rad: NDArray[np.float64]
    times: Time

    def summary_arcmin(self) -> dict[str, tuple[float, float]]:
        """Mean and standard deviation of the total, pointing and roll errors, arcmin (the form of
        Fowler 2013's headline numbers: Aptina 1.5 +- 0.6 total)."""
        return {name: (float(np.mean(v) / ARCMIN), float(np.std(v) / ARCMIN))
                for name, v in (("total", self.total_rad), ("pointing", self.pointing_rad), ("roll", self.roll_rad))}


def repeatability(times: Time, rotations: list[Rotation], site: Site) -> Repeatability:
    """Fixed-mount repeatability of a sequence of solved images (module docstring).

    Parameters
    ----------
    times : Time, shape (n,)
        Image times (UTC), n >= 2.
    rotations : list of Rotation
        ``rot_cam_from_icrs`` of each image.
    site : Site
    """
    if times.isscalar or len(times) != len(rotations) or len(rotations) < 2:
        raise InvalidInputError(f"need one time per attitude and at least two images, got "
                                f"{1 if times.isscalar else len(times)} times and {len(rotations)} attitudes")
    enu = [rotation_enu_from_icrs(t, site) for t in times]
    per_image = Rotation.concatenate([r * e.inv() for r, e in zip(rotations, enu, strict=True)])
    mount = per_image.mean()
    spread = (per_image * mount.inv()).as_rotvec()
    n = len(rotations)
    se_axes = np.std(spread, axis=0, ddof=1) / math.sqrt(n)
    errors = np.stack([(r * (mount * e).inv()).as_rotvec() for r, e in zip(rotations, enu, strict=True)])
    return Repeatability(mount=mount, mount_standard_error_rad=float(np.sqrt(np.mean(se_axes**2))),
                         total_rad=np.linalg.norm(errors, axis=1), pointing_rad=np.hypot(errors[:, 0], errors[:, 1]),
                         roll_rad=np.abs(errors[:, 2]), times=times)


def error_budget(result: Repeatability, *, lens_sigma_px: float, pixel_scale_arcsec: float,
                 threshold_rad: float = 0.0, atmosphere_rad: float = BENNETT_ACCURACY_RAD) -> dict[str, float]:
    """Fowler 2013 Table 9.5: the components and their linear and root-sum-square totals, radians.

    Parameters
    ----------
    lens_sigma_px : float
        Calibration 1-sigma reprojection error (px), converted with ``pixel_scale_arcsec``.
    threshold_rad : float
        Change of the mean star-to-spot deviation when the detection threshold is lowered (Ch. 9
        §VII; 0.15 arcmin in the thesis), measured by the caller.
    atmosphere_rad : float
        Refraction model accuracy (Bennett: 4.2 arcsec).
    """
    lens = lens_sigma_px * pixel_scale_arcsec * math.pi / (180.0 * 3600.0)
    parts = {"truth": result.mount_standard_error_rad, "threshold": float(threshold_rad), "lens": lens,
             "atmosphere": float(atmosphere_rad)}
    values = np.array(list(parts.values()))
    return {**parts, "linear_sum": float(values.sum()), "rss": float(np.sqrt(np.sum(values**2))),
            "observed_total": float(np.mean(result.total_rad))}
