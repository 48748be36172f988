"""Epoch propagation against astropy's SkyCoord.apply_space_motion (ERFA pmsafe).

astropy needs a distance: without one, ERFA substitutes a tiny parallax and warns "distance
overridden", which pytest turns into an error. With zero radial velocity our direction does not
depend on the distance, so any positive one would do; we give it the catalog's parallax and test
stars with parallax > 1 mas (plus Barnard's star).
"""

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import Distance, SkyCoord
from astropy.time import Time

from startrack.catalog import StarCatalog, load_catalog
from startrack.frames import angle_between
from startrack.units import MAS

AU_KM_S_YR = 4.740470463533348  # km/s for 1 AU/yr (the "A" of mu_r = v_r * parallax / A)
BARNARD, SIRIUS, ALPHA_CEN_A, GROOMBRIDGE_1830 = 87937, 32349, 71683, 57939


@pytest.fixture(scope="module")
def sample() -> StarCatalog:
    catalog = load_catalog()
    rng = np.random.default_rng(2025)
    named = np.flatnonzero(np.isin(catalog.hip, [BARNARD, SIRIUS, ALPHA_CEN_A, GROOMBRIDGE_1830]))
    near = rng.choice(np.flatnonzero(catalog.parallax_mas > 1.0), 300, replace=False)
    return catalog.take(np.concatenate([named, near]))


def astropy_motion(cat: StarCatalog, epoch: float) -> SkyCoord:
    start = SkyCoord(
        ra=cat.ra_rad * u.rad, dec=cat.dec_rad * u.rad,
        pm_ra_cosdec=cat.pm_ra_mas_yr * u.mas / u.yr, pm_dec=cat.pm_dec_mas_yr * u.mas / u.yr,
        distance=Distance(parallax=cat.parallax_mas * u.mas), radial_velocity=0 * u.km / u.s,
        obstime=Time(cat.epoch_jyear, format="jyear", scale="tdb"), frame="icrs",
    )
    # TDB: a TT/UTC epoch in 2050 makes ERFA warn about leap seconds ("dubious year").
    return start.apply_space_motion(new_obstime=Time(epoch, format="jyear", scale="tdb"))


@pytest.mark.parametrize("epoch", [2000.0, 2050.0])
def test_vectors_match_astropy(sample, epoch):
    expected = astropy_motion(sample, epoch).cartesian.xyz.value.T
    err = angle_between(sample.vectors(epoch), expected)
    assert np.max(err) < 1 * MAS
    barnard = np.flatnonzero(sample.hip == BARNARD)[0]
    moved = angle_between(sample.vectors(epoch)[barnard], sample.vectors()[barnard])
    assert moved > 10.0 * (epoch - 1991.25) * 1000 * MAS  # it really moved (> 10 arcsec/yr)


@pytest.mark.parametrize("epoch", [2000.0, 2050.0])
def test_propagated_state_matches_astropy(sample, epoch):
    expected = astropy_motion(sample, epoch)
    moved = sample.propagated(Time(epoch, format="jyear", scale="tdb"))
    assert moved.epoch_jyear == pytest.approx(epoch, abs=1e-9)
    dra = (moved.ra_rad - expected.ra.rad + np.pi) % (2 * np.pi) - np.pi
    assert np.max(np.abs(dra * np.cos(moved.dec_rad))) < 1 * MAS
    assert np.max(np.abs(moved.dec_rad - expected.dec.rad)) < 1 * MAS
    pm_tol = 1e-3  # mas/yr
    np.testing.assert_allclose(moved.pm_ra_mas_yr, expected.pm_ra_cosdec.to_value("mas/yr"),
                               atol=pm_tol)
    np.testing.assert_allclose(moved.pm_dec_mas_yr, expected.pm_dec.to_value("mas/yr"),
                               atol=pm_tol)
    mu_r = expected.radial_velocity.to_value("km/s") * moved.parallax_mas / AU_KM_S_YR
    np.testing.assert_allclose(moved.pm_radial_mas_yr, mu_r, atol=pm_tol)
    # ERFA's light-time terms change the distance by ~1e-6 of itself over 60 years.
    np.testing.assert_allclose(moved.parallax_mas, expected.distance.parallax.to_value("mas"),
                               rtol=1e-5)


def test_two_steps_equal_one(sample):
    direct = sample.propagated(2050.0)
    stepped = sample.propagated(2000.0).propagated(2050.0)
    assert np.max(angle_between(direct.vectors(), stepped.vectors())) < 1e-6 * MAS
    back = direct.propagated(1991.25)
    assert np.max(angle_between(back.vectors(), sample.vectors())) < 1e-6 * MAS
    np.testing.assert_allclose(back.pm_ra_mas_yr, sample.pm_ra_mas_yr, atol=1e-6)
    np.testing.assert_allclose(stepped.vectors(), sample.vectors(2050.0), atol=1e-15)


@pytest.mark.parametrize("scale", ["tdb", "tt", "utc"])
def test_time_and_float_epochs_agree(sample, scale):
    # A future TT/UTC Time needs leap seconds ERFA does not know; that must not warn.
    as_time = sample.vectors(Time(2050.0, format="jyear", scale=scale))
    # UTC differs from TDB by about 70 s: 0.02 mas of Barnard's star's motion.
    assert np.max(angle_between(as_time, sample.vectors(2050.0))) < 0.1 * MAS
