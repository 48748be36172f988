"""The IAU constellation a direction lies in: Delporte's boundaries of 1930, as tabulated by
Roman 1987 (CDS VI/42) in the mean equator and equinox of B1875.0.

A direction (ICRS, taken as the mean equator and equinox of J2000.0: the frame bias of 0.02 arcsec
is far below what a boundary look-up resolves) is precessed to B1875.0 with the precession angles
of the IAU's constants of 1976 (Lieske et al. 1977, as Meeus 1998 ch. 21 gives them), then the
table is read as Roman describes: the first row, in the table's order (declination of the lower
edge falling), whose lower declination is at or below the direction's and whose right-ascension
interval holds it names the constellation. Roman's table rounds the boundaries to 1e-4 h and
1e-4 deg: up to 2.7 arcsec of right ascension on the equator and 0.18 arcsec of declination.

astropy's ``get_constellation`` precesses through a geocentric frame at B1875.0 and so also
shifts a direction by that date's annual aberration (up to 20.5 arcsec): the two agree except
within that distance of a boundary (the tests measure it).

The table and the IAU names are read from the data files that astropy installs with
``astropy.coordinates`` (the same files its ``get_constellation`` reads), found without importing
astropy.coordinates, whose import costs a solve command a noticeable part of its start.
"""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from ..errors import StartrackError
from ..frames import radec_to_vector, vector_to_radec
from ..units import ARCSEC, J2000_JD

B1875_JD = 2405889.258550475
"""Julian date of the Besselian epoch B1875.0, the equinox of Roman's boundaries."""
TABLE_FILE = "constellation_data_roman87.dat"
"""astropy.coordinates' copy of Roman's table: RA from, RA to (h), lower Dec (deg), abbreviation."""
NAMES_FILE = "constellation_names.dat"
"""astropy.coordinates' list of the IAU abbreviations and names."""


def _data_file(name: str) -> Path:
    """The path of one of astropy.coordinates' data files (``astropy`` itself is not imported)."""
    spec = importlib.util.find_spec("astropy")
    folders = list(spec.submodule_search_locations or []) if spec else []
    for folder in folders:
        path = Path(folder) / "coordinates" / "data" / name
        if path.is_file():
            return path
    raise StartrackError(f"astropy's constellation data file {name} is not installed (looked in {folders}); "
                         "reinstall astropy")


@functools.cache
def _boundaries() -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.str_]]:
    """Roman's rows: lower and upper right ascension (h), lower declination (deg), abbreviation."""
    rows = [line.split() for line in _data_file(TABLE_FILE).read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    ra_low, ra_high, dec_low = (np.array([float(r[k]) for r in rows]) for k in range(3))
    return ra_low, ra_high, dec_low, np.array([r[3] for r in rows])


@functools.cache
def _names() -> dict[str, str]:
    """IAU abbreviation -> the constellation's name."""
    lines = _data_file(NAMES_FILE).read_text().splitlines()
    return dict(line.split(None, 1) for line in lines if line.strip() and not line.startswith("#"))


def precession_iau1976(jd: float) -> Rotation:
    """The rotation taking a J2000.0 mean-equator vector to the mean equator and equinox of the
    Julian date ``jd``: the axes turned by ``-zeta`` about z, ``theta`` about y and ``-z`` about z,
    the angles of Lieske et al. 1977 (Meeus 1998 ch. 21). Its error grows as the cube of the time
    from J2000.0: below an arcsecond at B1875.0 (against astropy's FK5, in the tests)."""
    t = (jd - J2000_JD) / 36525.0
    zeta = (2306.2181 * t + 0.30188 * t**2 + 0.017998 * t**3) * ARCSEC
    z = (2306.2181 * t + 1.09468 * t**2 + 0.018203 * t**3) * ARCSEC
    theta = (2004.3109 * t - 0.42665 * t**2 - 0.041833 * t**3) * ARCSEC
    return Rotation.from_euler("ZYZ", [z, -theta, zeta])  # turning the axes by a angle turns vectors by -a


def constellation_of(ra_deg: ArrayLike, dec_deg: ArrayLike, *, abbreviation: bool = False) -> str | NDArray[np.str_]:
    """The IAU constellation of ICRS directions.

    Parameters
    ----------
    ra_deg, dec_deg : float or array_like, shape (N,)
        Right ascension and declination, ICRS, deg (broadcast together).
    abbreviation : bool
        Give the IAU's three-letter abbreviation ("Per") instead of the name ("Perseus").

    Returns
    -------
    str, or ndarray of str of the broadcast shape
        A str for scalar inputs.
    """
    ra, dec = np.broadcast_arrays(np.asarray(ra_deg, dtype=float), np.asarray(dec_deg, dtype=float))
    if not (np.all(np.isfinite(ra)) and np.all(np.isfinite(dec))):
        raise StartrackError("constellation_of needs finite right ascensions and declinations")
    ra_1875, dec_1875 = _to_b1875(np.radians(ra.ravel()), np.radians(dec.ravel()))
    ra_low, ra_high, dec_low, short = _boundaries()
    inside = ((dec_low[:, None] <= dec_1875) & (ra_low[:, None] <= ra_1875) & (ra_1875 < ra_high[:, None]))
    found = short[np.argmax(inside, axis=0)]  # the first row that holds each direction (the table covers the sky)
    out = found if abbreviation else np.array([_names()[s] for s in found])
    return str(out[0]) if ra.ndim == 0 else out.reshape(ra.shape)


def _to_b1875(ra_rad: NDArray[np.float64], dec_rad: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """Right ascension (h, in [0, 24)) and declination (deg) in the mean equator and equinox of
    B1875.0 of J2000.0 directions given in radians."""
    ra, dec = vector_to_radec(precession_iau1976(B1875_JD).apply(radec_to_vector(ra_rad, dec_rad)))
    return np.degrees(ra) / 15.0 % 24.0, np.degrees(dec)
