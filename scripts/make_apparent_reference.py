"""Generate the astropy reference data for the apparent-place test (tests/calibrate).

Run from the repository root:  .venv/bin/python scripts/make_apparent_reference.py

For a fixed set of Hipparcos-2 stars (a few with the largest proper motions and parallaxes, the
rest drawn with a fixed seed among stars brighter than V 7) and times from 1990 to 2050, astropy's
SkyCoord moves each star to the time (``apply_space_motion``, zero radial velocity) and transforms
it to GCRS (geocentric apparent direction on ICRS axes: parallax, light deflection by the Sun,
annual aberration), to GCRS with an observer velocity (orbital aberration) and to TETE (true
equator and equinox of date). The output, tests/calibrate/data/apparent_reference.json, holds the
catalog inputs and astropy's answers in degrees; the test rebuilds the catalog from it and compares
startrack.calibrate._apparent to it.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.coordinates import GCRS, ICRS, TETE, CartesianDifferential, CartesianRepresentation, SkyCoord
from astropy.time import Time
from erfa import ErfaWarning

from startrack.catalog import load_catalog

OUT = Path(__file__).resolve().parents[1] / "tests" / "calibrate" / "data" / "apparent_reference.json"
NOTABLE_HIP = [87937, 104214, 71683, 32349, 24436, 54035, 57939, 439, 3829, 19849]
"""Barnard's star, 61 Cyg A, alpha Cen A, Sirius, Rigel, Lalande 21185, Groombridge 1830,
HIP 439, van Maanen's star, omicron2 Eri: large proper motions and parallaxes."""
TIMES_UTC = ["1990-01-01T00:00:00", "1999-07-15T06:00:00", "2005-03-20T12:00:00",
             "2012-10-05T03:30:00", "2024-06-21T18:00:00", "2037-12-01T00:00:00",
             "2050-01-01T00:00:00"]
ORBIT_POSITION_M = [4.0e6, -3.0e6, 4.5e6]
ORBIT_VELOCITY_M_S = [5200.0, 4100.0, -3500.0]


def _stars() -> dict[str, list]:
    cat = load_catalog()
    rng = np.random.default_rng(20250701)
    bright = np.flatnonzero((cat.v_mag < 7.0) & (cat.parallax_mas > 1.0))
    rows = list(np.flatnonzero(np.isin(cat.hip, NOTABLE_HIP))) + list(rng.choice(bright, 30, replace=False))
    sel = cat.take(np.array(rows))
    return {"hip": sel.hip.tolist(), "ra_deg": np.degrees(sel.ra_rad).tolist(),
            "dec_deg": np.degrees(sel.dec_rad).tolist(), "pm_ra_mas_yr": sel.pm_ra_mas_yr.tolist(),
            "pm_dec_mas_yr": sel.pm_dec_mas_yr.tolist(), "parallax_mas": sel.parallax_mas.tolist(),
            "epoch_jyear": sel.epoch_jyear}


def _radec(coord) -> list[list[float]]:
    sph = coord.represent_as("unitspherical")
    return [sph.lon.to_value(u.deg).tolist(), sph.lat.to_value(u.deg).tolist()]


def _reference(stars: dict[str, list], time_utc: str) -> dict[str, object]:
    t = Time(time_utc, scale="utc")
    coord = SkyCoord(ra=stars["ra_deg"] * u.deg, dec=stars["dec_deg"] * u.deg,
                     pm_ra_cosdec=stars["pm_ra_mas_yr"] * u.mas / u.yr,
                     pm_dec=stars["pm_dec_mas_yr"] * u.mas / u.yr,
                     distance=(1000.0 / np.asarray(stars["parallax_mas"])) * u.pc,
                     radial_velocity=np.zeros(len(stars["hip"])) * u.km / u.s, frame=ICRS,
                     obstime=Time(stars["epoch_jyear"], format="jyear", scale="tdb"))
    moved = coord.apply_space_motion(new_obstime=t)
    obs_pos = CartesianRepresentation(ORBIT_POSITION_M * u.m)
    obs_vel = CartesianDifferential(ORBIT_VELOCITY_M_S * u.m / u.s)
    return {"time_utc": time_utc,
            "astrometric": _radec(moved.icrs),
            "gcrs": _radec(moved.transform_to(GCRS(obstime=t))),
            "gcrs_orbit": _radec(moved.transform_to(GCRS(obstime=t, obsgeoloc=obs_pos,
                                                         obsgeovel=obs_vel))),
            "tete": _radec(moved.transform_to(TETE(obstime=t)))}


def main() -> None:
    stars = _stars()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ErfaWarning)  # dubious year: no leap seconds for 2050 yet
        refs = [_reference(stars, t) for t in TIMES_UTC]
    data = {"generator": "scripts/make_apparent_reference.py", "stars": stars,
            "orbit_position_m": ORBIT_POSITION_M, "orbit_velocity_m_s": ORBIT_VELOCITY_M_S,
            "times": refs}
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(data, indent=1))
    print(f"wrote {OUT} ({len(stars['hip'])} stars x {len(refs)} times)")


if __name__ == "__main__":
    main()
