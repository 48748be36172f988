"""The IAU constellation of a direction (startrack.catalog.constellation_of), against astropy."""

from __future__ import annotations

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import FK5, SkyCoord
from astropy.time import Time

from startrack.catalog import constellation_of
from startrack.catalog._constellations import B1875_JD, _to_b1875
from startrack.errors import StartrackError

ARCSEC_DEG = 1.0 / 3600.0


def _random_directions(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Uniform on the sphere: right ascension and declination, deg."""
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    return np.degrees(np.arctan2(v[:, 1], v[:, 0])) % 360.0, np.degrees(np.arcsin(v[:, 2]))


def test_the_precession_to_b1875_agrees_with_astropys_fk5_to_an_arcsecond():
    ra, dec = _random_directions(500, seed=3)
    ours_ra_h, ours_dec = _to_b1875(np.radians(ra), np.radians(dec))
    b1875 = FK5(equinox=Time(B1875_JD, format="jd", scale="tt"))
    fk5 = SkyCoord(ra * u.deg, dec * u.deg, frame="icrs").transform_to(b1875)
    ours = SkyCoord(ours_ra_h * 15.0 * u.deg, ours_dec * u.deg)
    separation = ours.separation(SkyCoord(fk5.ra, fk5.dec)).to(u.arcsec).value
    assert separation.max() < 1.0  # arcsec: IAU 1976 precession and the ICRS frame bias apart


def test_every_direction_away_from_a_boundary_is_named_as_astropy_names_it():
    """astropy's ``get_constellation`` goes through a geocentric frame at B1875 and so adds the
    annual aberration of that date (up to 20.5 arcsec; astropy issue 9855 and PR 9856 discuss
    it); Roman's boundaries are mean places. Directions more than 40 arcsec from a boundary
    must agree; the few that differ must lie within 40 arcsec of one."""
    ra, dec = _random_directions(20_000, seed=1)
    ours = constellation_of(ra, dec, abbreviation=True)
    theirs = SkyCoord(ra * u.deg, dec * u.deg, frame="icrs").get_constellation(short_name=True)
    step = 40.0 * ARCSEC_DEG
    near = np.zeros(ra.size, dtype=bool)
    for d_ra, d_dec in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)):
        near |= constellation_of(ra + d_ra / np.cos(np.radians(dec)), np.clip(dec + d_dec, -90, 90),
                                 abbreviation=True) != ours
    differ = ours != theirs
    assert not np.any(differ & ~near)
    assert differ.sum() < 0.005 * ra.size and len(set(ours)) == 88  # a few near edges; every constellation met


@pytest.mark.parametrize(("ra_deg", "dec_deg", "name"), [
    (88.7929, 7.4071, "Orion"),  # Betelgeuse
    (37.9546, 89.2641, "Ursa Minor"),  # Polaris
    (101.2872, -16.7161, "Canis Major"),  # Sirius
    (219.9021, -60.8340, "Centaurus"),  # alpha Centauri
    (279.2347, 38.7837, "Lyra"),  # Vega
    (56.75, 24.12, "Taurus"),  # the Pleiades
    (0.0, -90.0, "Octans"),
])
def test_bright_stars_lie_in_their_constellations(ra_deg, dec_deg, name):
    assert constellation_of(ra_deg, dec_deg) == name


def test_arrays_keep_their_shape_and_scalars_give_a_str():
    names = constellation_of(np.array([[88.79, 279.23]]), np.array([[7.41, 38.78]]), abbreviation=True)
    assert names.shape == (1, 2) and names.tolist() == [["Ori", "Lyr"]]
    assert isinstance(constellation_of(88.79, 7.41), str)


def test_a_direction_that_is_not_finite_is_refused():
    with pytest.raises(StartrackError, match="finite"):
        constellation_of(np.nan, 0.0)
