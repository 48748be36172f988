"""StarCatalog: selection, magnitude filter, unit vectors (against astropy)."""

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import SkyCoord

from startrack.catalog import StarCatalog, load_catalog
from startrack.errors import InvalidInputError
from startrack.frames import angle_between

NUMERIC = 1e-12  # radians: float64 rounding


@pytest.fixture(scope="module")
def catalog() -> StarCatalog:
    return load_catalog()


def test_vectors_match_astropy_cartesian(catalog):
    rng = np.random.default_rng(7)
    sample = catalog.take(rng.choice(len(catalog), 500, replace=False))
    expected = SkyCoord(ra=sample.ra_rad * u.rad, dec=sample.dec_rad * u.rad, frame="icrs")
    xyz = expected.cartesian.xyz.value.T
    np.testing.assert_allclose(sample.vectors(), xyz, atol=NUMERIC)
    np.testing.assert_allclose(np.linalg.norm(sample.vectors(), axis=1), 1.0, atol=NUMERIC)


def test_vectors_at_own_epoch_are_unpropagated(catalog):
    head = catalog.take(slice(0, 100))
    np.testing.assert_array_equal(head.vectors(1991.25), head.vectors())


@pytest.mark.parametrize("band", ["v", "hp"])
def test_brighter_than(catalog, band):
    mags = catalog.magnitudes(band)
    bright = catalog.brighter_than(6.0, band=band)
    assert len(bright) == np.count_nonzero(mags <= 6.0)
    assert np.all(bright.magnitudes(band) <= 6.0)
    assert 4500 < len(bright) < 5500  # about 5,000 naked-eye stars (Huffman 2006: 5,060 in SKY2000)
    np.testing.assert_array_equal(bright.hip, catalog.hip[mags <= 6.0])


def test_brighter_than_rejects_unknown_band(catalog):
    with pytest.raises(InvalidInputError, match="band"):
        catalog.brighter_than(6.0, band="g")


def test_take_by_mask_indices_and_slice(catalog):
    mask = catalog.hip % 2 == 0
    evens = catalog.take(mask)
    assert len(evens) == mask.sum() and np.all(evens.hip % 2 == 0)
    picked = catalog.take([2, 0])
    np.testing.assert_array_equal(picked.hip, catalog.hip[[2, 0]])
    assert picked.epoch_jyear == catalog.epoch_jyear
    assert len(catalog.take([])) == 0
    with pytest.raises(InvalidInputError, match="boolean index"):
        catalog.take(mask[:-1])


def test_from_positions_and_validation():
    cat = StarCatalog.from_positions([0.0, 1.0], [0.0, 0.5], [3.0, 4.0])
    assert len(cat) == 2 and cat.epoch_jyear == 2000.0
    np.testing.assert_array_equal(cat.hip, [1, 2])
    assert angle_between(cat.vectors()[0], [1.0, 0.0, 0.0]) < NUMERIC
    with pytest.raises(InvalidInputError, match="all arrays must be"):
        StarCatalog(hip=[1, 2], ra_rad=[0.0], dec_rad=[0.0, 0.0], pm_ra_mas_yr=[0, 0],
                    pm_dec_mas_yr=[0, 0], parallax_mas=[0, 0], hp_mag=[1, 1], b_v=[0, 0],
                    v_mag=[1, 1], variable=[False, False], epoch_jyear=2000.0)
    with pytest.raises(InvalidInputError, match="epoch"):
        cat.vectors("soon")
