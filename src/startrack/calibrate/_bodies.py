"""Flags for what can spoil a frame: variable stars among the matches, and the Sun, Moon and bright
planets near the field (Jacobs 1995 §7.4 and §7.6: variables act as false or missing stars; a bright
body within the baffle's exclusion angle, 28 deg for Sunsat, floods the image).

The ephemerides are astropy's built-in ones (ERFA's ``epv00`` / ``plan94`` and a lunar series;
offline, arcminute-level, ample for flags).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from astropy.coordinates import get_body
from astropy.time import Time
from erfa import ErfaWarning
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..catalog import load_catalog
from ..frames import angle_between, boresight, radec_to_vector

BRIGHT_BODIES = ("sun", "moon", "mercury", "venus", "mars", "jupiter", "saturn")
SUNSAT_EXCLUSION_DEG = 28.1
"""Jacobs 1995 §7.6: the smallest off-axis angle at which direct light reaches the lens past the baffle."""


@dataclass(frozen=True)
class BodyFlag:
    """A bright body and its angle from the boresight.

    Attributes
    ----------
    name : str
    separation_deg : float
        Angle between the boresight and the body (geocentric), degrees.
    near : bool
        Within the radius asked for.
    """

    name: str
    separation_deg: float
    near: bool


def body_directions(time: Time, names: tuple[str, ...] = BRIGHT_BODIES) -> dict[str, NDArray[np.float64]]:
    """Geocentric apparent directions (ICRS axes, unit vectors) of solar-system bodies at ``time``."""
    out = {}
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=ErfaWarning)
        for name in names:
            coord = get_body(name, time, ephemeris="builtin")
            out[name] = radec_to_vector(coord.ra.rad, coord.dec.rad)
    return out


def bright_bodies_near(rot_cam_from_icrs: Rotation, time: Time, radius_deg: float = SUNSAT_EXCLUSION_DEG,
                       names: tuple[str, ...] = BRIGHT_BODIES) -> list[BodyFlag]:
    """Every body of ``names`` with its angle from the boresight, nearest first; ``near`` marks those
    within ``radius_deg`` (a baffle's exclusion angle, or the field radius plus a margin)."""
    axis = boresight(rot_cam_from_icrs)
    flags = [BodyFlag(name, math.degrees(float(angle_between(axis, v))), False)
             for name, v in body_directions(time, names).items()]
    flags = [BodyFlag(f.name, f.separation_deg, f.separation_deg <= radius_deg) for f in flags]
    return sorted(flags, key=lambda f: f.separation_deg)


def variable_flags(hip: ArrayLike) -> NDArray[np.bool_]:
    """True for each Hipparcos number that the catalog marks as a known variable (its magnitude in
    the image may differ from the catalog's)."""
    cat = load_catalog()
    hip = np.asarray(hip, dtype=np.int64)
    order = np.argsort(cat.hip)
    pos = np.clip(np.searchsorted(cat.hip[order], hip), 0, len(cat) - 1)
    found = cat.hip[order][pos] == hip
    return found & cat.variable[order][pos]
