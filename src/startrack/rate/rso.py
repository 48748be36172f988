"""Objects that move unlike the stars: the three RSO indicators of seed 001 chapter 4.

Seed 001 ch. 4 "RSO Indicators", eqs. 4.11-4.15 (notes seed-001-004 §1.22). Every star streak
of one image is the same rotation seen at a different place; a resident space object (RSO), an
overlapping pair or a corrupted streak is not. Per streak:

(a) **centre of rotation**: the distance of the common centre of rotation from the streak's
    perpendicular bisector (px, :mod:`.grouping`); when the streaks are parallel (centre at
    infinity), the streak's slope relative to the dominant direction (rad);
(b) **angular displacement**: the angle the streak turns through about the centre of rotation,
    ``phi_i = angle(p_i1 - X, p_i2 - X)`` (rad); when parallel, the streak length (px);
(c) **combined**: the OLAE residual of the catalog-free rate (:mod:`.catalog_free`), which
    captures axis and angle together.

A streak is flagged by an indicator when its robust z-score ``|x - median| / max(1.4826 MAD,
floor)`` exceeds k (seed: 2.5). The floors are the seed's "lower bound on the variance",
characterised on RSO-free images: here derived from the endpoint precision ``endpoint_sigma_px``
(default 0.3 px) so that all-agreeing streaks raise no false alarm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .catalog_free import K_SIGMA, robust_z
from .grouping import CentreOfRotation

INDICATORS = ("centre_of_rotation", "angular_displacement", "combined")


@dataclass(frozen=True)
class RsoIndicators:
    """Indicator values, z-scores and flags per streak (N,) for the three indicators.

    ``values``, ``z`` and ``flags`` map each name of :data:`INDICATORS` to an (N,) array;
    ``parallel`` says whether the slope and length replaced the centre-of-rotation forms.
    ``candidates`` are the streak indices flagged by the combined indicator.
    """

    values: dict[str, NDArray[np.float64]]
    z: dict[str, NDArray[np.float64]]
    flags: dict[str, NDArray[np.bool_]]
    parallel: bool

    @property
    def candidates(self) -> NDArray[np.intp]:
        return np.flatnonzero(self.flags["combined"])


def _turn_angles(first: NDArray, second: NDArray, centre: NDArray) -> NDArray[np.float64]:
    """Angles (N,) between the vectors from the centre to each end (stable atan2 form)."""
    u, v = first - centre, second - centre
    return np.abs(np.arctan2(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0], np.sum(u * v, axis=1)))


def _slopes(first: NDArray, second: NDArray, axis: NDArray) -> NDArray[np.float64]:
    """Signed angle (N,) of each streak's direction from the dominant one (sign-free, in +-pi/2)."""
    d = second - first
    angle = np.arctan2(d[:, 1], d[:, 0]) - np.arctan2(axis[1], axis[0])
    return (angle + 0.5 * np.pi) % np.pi - 0.5 * np.pi


def rso_indicators(
    first_xy: ArrayLike,
    second_xy: ArrayLike,
    cor: CentreOfRotation,
    olae_residuals: ArrayLike,
    pixel_angle_rad: float,
    *,
    k_sigma: float = K_SIGMA,
    endpoint_sigma_px: float = 0.3,
    parallel: bool | None = None,
) -> RsoIndicators:
    """The three indicators for N streaks (ends (N, 2) each, in the grouped order A, B).

    ``pixel_angle_rad`` converts the endpoint precision into the OLAE residual floor
    (``2 sqrt(2) endpoint_sigma`` pixel angles). ``parallel`` True forces the slope and length
    forms even when a finite centre was fitted (None: only when ``cor`` is parallel). With the spin
    axis near the focal plane the star paths are conics whose bisectors cross at a point that is
    no centre of rotation, so the centre-of-rotation forms mislead there (:func:`.streak_rate.streak_rate`
    passes True when the fitted axis is more than 63 deg from the boresight).
    """
    p1, p2 = np.asarray(first_xy, dtype=float), np.asarray(second_xy, dtype=float)
    lengths = np.linalg.norm(p2 - p1, axis=1)
    scale = float(np.median(lengths))
    far = cor.parallel or bool(parallel)
    if far:
        cor_values, cor_floor = _slopes(p1, p2, cor.direction), 2.0 * endpoint_sigma_px / scale
        disp_values, disp_floor = lengths, 2.0 * endpoint_sigma_px
    else:
        cor_values, cor_floor = cor.residual_px, endpoint_sigma_px
        radius = np.linalg.norm(0.5 * (p1 + p2) - cor.xy, axis=1)
        disp_values, disp_floor = _turn_angles(p1, p2, cor.xy), 2.0 * endpoint_sigma_px / float(np.median(radius))
    combined = np.asarray(olae_residuals, dtype=float)
    values = {"centre_of_rotation": cor_values, "angular_displacement": disp_values, "combined": combined}
    floors = [cor_floor, disp_floor, 2.0 * np.sqrt(2.0) * endpoint_sigma_px * pixel_angle_rad]
    z = {name: robust_z(values[name], floor) for name, floor in zip(INDICATORS, floors, strict=True)}
    flags = {name: np.abs(z[name]) > k_sigma for name in INDICATORS}
    return RsoIndicators(values, z, flags, far)
