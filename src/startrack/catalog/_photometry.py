"""Johnson V from Hipparcos Hp and B-V, and the variability rule.

The Hp passband is much wider than Johnson V, so ``V - Hp`` depends on colour. We use the
published relation of Bessell (2000), *PASP* 112, 961, Table 2 ("Relation between BT-VT and
Hipparcos/Tycho data for B-G main-sequence stars and K-M giants"), which tabulates
``del(B-V) = (B-V) - (BT-VT)`` and ``V - Hp`` on a grid of Tycho colour ``BT - VT`` from -0.25 to
2.00 in steps of 0.05. Adding ``del(B-V)`` to the grid gives the Johnson ``B - V`` of each row, so
the table becomes ``V - Hp`` as a function of Johnson ``B - V`` (monotonic, -0.22 to 1.66), which
we interpolate linearly and hold constant beyond its ends (red M stars have no reliable relation).
Checked against the ESA (1997) Johnson V of Arcturus, Aldebaran, Pollux and Polaris to 0.02 mag.
Hp of the very brightest stars is itself off (Sirius: Hp = -1.09 against V = -1.46).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

# Bessell (2000) Table 2, columns del(B-V) and V-Hp in millimagnitudes, for BT-VT = -0.25 .. 2.00.
_BT_VT = np.round(np.arange(-0.25, 2.0001, 0.05), 3)
_DEL_BV_MMAG = np.array([
    31, 21, 11, 5, 2, -5, -10, -17, -20, -21, -23, -25, -25, -26, -30, -35, -45, -51, -60, -68,
    -76, -85, -94, -104, -113, -122, -131, -142, -154, -166, -178, -189, -199, -210, -222, -234,
    -245, -256, -266, -277, -288, -299, -309, -320, -331, -342,
])
_V_MINUS_HP_MMAG = np.array([
    66, 51, 36, 21, 6, -11, -25, -38, -48, -58, -69, -79, -87, -94, -101, -108, -114, -120, -127,
    -131, -134, -137, -142, -147, -151, -155, -158, -157, -160, -162, -164, -166, -166, -165, -164,
    -161, -157, -153, -148, -143, -137, -131, -125, -119, -112, -106,
])
JOHNSON_BV_GRID: NDArray[np.float64] = _BT_VT + _DEL_BV_MMAG / 1000.0
"""Johnson B-V of the Bessell (2000) Table 2 rows, increasing."""
V_MINUS_HP_GRID: NDArray[np.float64] = _V_MINUS_HP_MMAG / 1000.0
"""V - Hp (mag) at :data:`JOHNSON_BV_GRID`."""


def v_from_hp(hp_mag: ArrayLike, b_v: ArrayLike) -> NDArray[np.float64]:
    """Estimated Johnson V (mag) from Hipparcos Hp and Johnson B-V, shapes (N,).

    ``V = Hp + (V - Hp)(B - V)`` from Bessell (2000) Table 2 (see the module docstring). Where
    ``b_v`` is NaN (no colour in the catalog) V falls back to Hp.
    """
    hp = np.asarray(hp_mag, dtype=float)
    bv = np.asarray(b_v, dtype=float)
    correction = np.interp(np.nan_to_num(bv, nan=0.0), JOHNSON_BV_GRID, V_MINUS_HP_GRID)
    return np.where(np.isnan(bv), hp, hp + correction)


def variability_flag(solution_type: ArrayLike, variability_annex: ArrayLike) -> NDArray[np.bool_]:
    """True for stars known to vary, from the hip2.dat columns Sn and VA (ESA I/311 ReadMe).

    A star is variable when it has an entry in the Hipparcos variability annex (``VA`` = 1 or 2),
    or when the solution type ``Sn = 10 d + s`` has bit 2 of ``d`` set ("variable in the system with
    amplitude > 0.2 mag"). The hip2.dat column named ``var`` is *not* used: it is the cosmic
    dispersion added to stochastic astrometric solutions, not a variability amplitude.
    """
    d = np.asarray(solution_type, dtype=np.int64) // 10
    return (np.asarray(variability_annex) > 0) | ((d & 2) != 0)
