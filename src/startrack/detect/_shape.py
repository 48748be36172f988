"""Spot shape: long and short axis, direction, and the test against the expected smear.

Jacobs 1995 §2.2.3: from the **unweighted** "base centre" of the
spot's pixels (lens aberration skews the intensity-weighted one), the second moments
``M20 = sum (x - x0)^2``, ``M02 = sum (y - y0)^2``, ``M11 = sum (x - x0)(y - y0)`` give the
direction of the long axis

    angle = 0.5 * atan2(2 M11, M20 - M02)          in (-90, 90] degrees,

measured in our image frame from +x towards +y (the seed measures from its mirrored +u axis).
The long axis ``a`` is the extent of the spot's pixels along that direction (furthest pixel
centres, plus one pixel for the pixels' own size) and ``b`` the extent across it.

Smear test (the seed's tracking case): with the expected smear vector d over the exposure (from
the previous and present attitudes, or the rate), accept when ``|(a - b) - |d|| < tolerance``
(2 px) and, for spots longer than 5 px beyond round, when the direction is within 30 degrees of
d's. Without a prediction (its matching case) accept ``a - b < max_axis_difference`` (12 px:
10 px of largest expected smear plus 2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._compiled import region_kernels
from ._label import Regions

DIRECTION_CHECK_PX = 5.0
"""Above this axis difference the smear direction is checked too (Jacobs 1995)."""


@dataclass(frozen=True)
class SpotShape:
    """Axes and direction of N spots, arrays of shape (N,).

    Attributes
    ----------
    major_px, minor_px : float
        Extent along the long and the short axis (a and b of Jacobs 1995), px.
    angle_deg : float
        Direction of the long axis from +x towards +y, in (-90, 90].
    """

    major_px: NDArray[np.float64]
    minor_px: NDArray[np.float64]
    angle_deg: NDArray[np.float64]


def spot_shape(regions: Regions) -> SpotShape:
    """Jacobs 1995 axes and direction of every region (module docstring); one compiled loop over
    the regions' pixels (:func:`.region_kernels.spot_axes`)."""
    axes = region_kernels().spot_axes(regions.starts, regions.x.astype(np.float64), regions.y.astype(np.float64))
    deg = np.degrees(axes[:, 2])
    return SpotShape(axes[:, 0], axes[:, 1], np.where(deg <= -90.0, deg + 180.0, deg))


def smear_ok(shape: SpotShape, smear_px: tuple[float, float] | None, tolerance_px: float,
             max_axis_difference_px: float | None, max_angle_deg: float) -> NDArray[np.bool_]:
    """Jacobs 1995's shape test (module docstring); all True when neither a smear vector nor a
    maximum axis difference is given."""
    diff = shape.major_px - shape.minor_px
    keep = np.ones(diff.shape, dtype=bool)
    if max_axis_difference_px is not None:
        keep &= diff < max_axis_difference_px
    if smear_px is None:
        return keep
    length = float(np.hypot(*smear_px))
    keep &= np.abs(diff - length) < tolerance_px
    expected = np.degrees(np.arctan2(smear_px[1], smear_px[0]))
    delta = (shape.angle_deg - expected + 90.0) % 180.0 - 90.0
    return keep & ((diff <= DIRECTION_CHECK_PX) | (np.abs(delta) < max_angle_deg))
