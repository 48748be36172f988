"""Double stars: the exact merge formulas (Huffman 2006 §5.5.4, corrected) and the real catalog."""

import dataclasses

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import SkyCoord

from startrack.catalog import StarCatalog, flag_doubles, load_catalog, merge_doubles
from startrack.errors import InvalidInputError
from startrack.frames import angle_between
from startrack.units import ARCSEC

MAG = 1.0
NUMERIC_MAG = 1e-12 * MAG


def pair_along_equator(separations_arcsec, v_mag, b_v=None) -> StarCatalog:
    ra = np.concatenate([[0.0], np.cumsum(separations_arcsec)]) * ARCSEC + 1.0
    cat = StarCatalog.from_positions(ra, 0.2, v_mag, hip=np.arange(len(ra)) + 100)
    return cat if b_v is None else dataclasses.replace(cat, b_v=b_v)


def test_two_stars_merge_with_exact_magnitude_and_direction():
    m1, m2 = 3.0, 4.2
    cat = pair_along_equator([5.0], [m2, m1])  # the fainter star first
    merged = merge_doubles(cat, 10 * ARCSEC)
    assert len(merged) == 1
    expected = m2 - 2.5 * np.log10(1 + 10 ** ((m2 - m1) / 2.5))
    assert merged.v_mag[0] == pytest.approx(expected, abs=NUMERIC_MAG)
    assert merged.hp_mag[0] == pytest.approx(expected, abs=NUMERIC_MAG)
    assert merged.hip[0] == 101  # the brighter star's number
    weights = 10 ** ((expected - np.array([m2, m1])) / 2.5)
    direction = weights @ cat.vectors()
    direction /= np.linalg.norm(direction)
    assert angle_between(merged.vectors()[0], direction) < 1e-9 * ARCSEC
    # the photocentre divides the pair in the flux ratio
    offset = angle_between(merged.vectors()[0], cat.vectors()[1])
    separation = angle_between(cat.vectors()[0], cat.vectors()[1])
    assert offset == pytest.approx(separation * weights[0], rel=1e-6)


def test_far_pair_is_kept_apart():
    cat = pair_along_equator([15.0], [3.0, 4.0])
    assert merge_doubles(cat, 10 * ARCSEC) is cat
    assert not flag_doubles(cat, 10 * ARCSEC).any()


def test_a_much_fainter_neighbour_flags_only_itself():
    cat = pair_along_equator([8.0, 600.0, 8.0], [3.0, 6.5, 4.0, 5.0])  # gaps of 3.5 and 1.0 mag
    np.testing.assert_array_equal(flag_doubles(cat, 10 * ARCSEC, max_delta_mag=3.0), [False, True, True, True])
    np.testing.assert_array_equal(flag_doubles(cat, 10 * ARCSEC), [True, True, True, True])


def test_colour_of_merged_pair():
    cat = pair_along_equator([2.0], [3.0, 3.0], b_v=[0.0, 1.0])
    merged = merge_doubles(cat, 10 * ARCSEC)
    v = -2.5 * np.log10(2 * 10 ** (-0.4 * 3.0))
    b = -2.5 * np.log10(10 ** (-0.4 * 3.0) + 10 ** (-0.4 * 4.0))
    assert merged.b_v[0] == pytest.approx(b - v, abs=NUMERIC_MAG)
    missing = merge_doubles(pair_along_equator([2.0], [3.0, 3.0], b_v=[0.0, np.nan]), 10 * ARCSEC)
    assert np.isnan(missing.b_v[0])


def test_chain_of_three_merges_into_one_group():
    # A-B and B-C are 8" apart, A-C 16": friends-of-friends puts all three in one entry.
    cat = pair_along_equator([8.0, 8.0, 600.0], [5.0, 4.0, 6.0, 2.0])
    flags = flag_doubles(cat, 10 * ARCSEC)
    np.testing.assert_array_equal(flags, [True, True, True, False])
    merged = merge_doubles(cat, 10 * ARCSEC)
    assert len(merged) == 2
    np.testing.assert_array_equal(merged.hip, [101, 103])  # input order, brightest's number
    total = -2.5 * np.log10(np.sum(10 ** (-0.4 * np.array([5.0, 4.0, 6.0]))))
    assert merged.v_mag[0] == pytest.approx(total, abs=NUMERIC_MAG)
    assert merged.v_mag[1] == 2.0


def test_rejects_bad_threshold():
    cat = pair_along_equator([5.0], [3.0, 4.0])
    with pytest.raises(InvalidInputError, match="min_separation_rad"):
        merge_doubles(cat, 0.0)


def test_real_catalog_pairs_closer_than_10_arcsec():
    catalog = load_catalog()
    limit = 10 * ARCSEC
    coords = SkyCoord(ra=catalog.ra_rad * u.rad, dec=catalog.dec_rad * u.rad)
    i, j, _, _ = coords.search_around_sky(coords, limit * u.rad)
    pairs = {(a, b) for a, b in zip(i.tolist(), j.tolist(), strict=True) if a < b}
    flags = flag_doubles(catalog, limit)
    assert len(pairs) == 13  # Hipparcos resolves few pairs this close; none below 5"
    assert flags.sum() == len({k for p in pairs for k in p})
    assert not flag_doubles(catalog, 5 * ARCSEC).any()
    merged = merge_doubles(catalog, limit)
    assert len(merged) == len(catalog) - len(pairs)  # no triples at 10"
    assert not flag_doubles(merged, limit).any()
    assert np.all(np.isfinite(merged.v_mag)) and np.all(np.isfinite(merged.vectors()))
