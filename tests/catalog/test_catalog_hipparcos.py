"""Loading Hipparcos-2: known stars, size, photometry, variability, the cache."""

from pathlib import Path

import numpy as np
import pytest

from startrack import cache
from startrack.catalog import StarCatalog, load_catalog
from startrack.catalog._hipparcos import CACHE_KIND, catalog_file, catalog_from_arrays, load_hip2_arrays, parse_hip2
from startrack.errors import InvalidInputError
from startrack.units import ARCSEC, DEG

MAG = 1.0  # magnitudes carry no unit; named for readable tolerances


@pytest.fixture(scope="module")
def catalog() -> StarCatalog:
    return load_catalog()  # memoised per process, cached on disk in the user cache


def star(catalog: StarCatalog, hip: int) -> StarCatalog:
    index = np.flatnonzero(catalog.hip == hip)
    assert len(index) == 1
    return catalog.take(index)


def test_size_and_epoch(catalog):
    assert len(catalog) == 117_955
    assert catalog.epoch_jyear == 1991.25
    assert np.all(np.diff(catalog.hip) > 0)
    assert catalog.hip[0] == 1 and catalog.hip[-1] == 120_404


# HIP, RA and Dec (deg, ICRS, epoch J1991.25: J2000 values moved back by proper motion), Hp.
KNOWN = [
    (32349, 101.28854, -16.71314, -1.0876),  # Sirius
    (91262, 279.23411, 38.78299, 0.0868),  # Vega
    (11767, 37.94614, 89.26414, 2.1077),  # Polaris
    (27989, 88.79287, 7.40704, 0.4997),  # Betelgeuse
]


@pytest.mark.parametrize(("hip", "ra_deg", "dec_deg", "hp"), KNOWN)
def test_known_stars(catalog, hip, ra_deg, dec_deg, hp):
    s = star(catalog, hip)
    assert abs(s.ra_rad[0] - ra_deg * DEG) * np.cos(s.dec_rad[0]) < 0.1 * ARCSEC
    assert abs(s.dec_rad[0] - dec_deg * DEG) < 0.1 * ARCSEC
    assert s.hp_mag[0] == pytest.approx(hp, abs=1e-4)


def test_sirius_reaches_its_j2000_place(catalog):
    s2000 = star(catalog, 32349).propagated(2000.0)
    ra, dec = s2000.ra_rad[0] / DEG, s2000.dec_rad[0] / DEG
    assert ra == pytest.approx(101.287155, abs=1e-5)
    assert dec == pytest.approx(-16.716116, abs=1e-5)


# Johnson V from ESA (1997) field H5, for constant stars with good colours.
@pytest.mark.parametrize(("hip", "v_mag"), [
    (69673, -0.05),  # Arcturus, K1.5 III
    (21421, 0.87),  # Aldebaran, K5 III
    (37826, 1.16),  # Pollux, K0 III
    (11767, 1.97),  # Polaris, F7 Ib (small amplitude)
    (24436, 0.18),  # Rigel, B8 Ia
])
def test_v_estimate(catalog, hip, v_mag):
    assert star(catalog, hip).v_mag[0] == pytest.approx(v_mag, abs=0.03 * MAG)


def test_missing_colour_falls_back_to_hp(catalog):
    missing = np.isnan(catalog.b_v)
    assert 1000 < missing.sum() < 1300
    np.testing.assert_array_equal(catalog.v_mag[missing], catalog.hp_mag[missing])
    assert np.all(np.isfinite(catalog.v_mag))


def test_variability_flags(catalog):
    assert star(catalog, 27989).variable[0]  # Betelgeuse, semiregular
    assert star(catalog, 11767).variable[0]  # Polaris, Cepheid
    assert not star(catalog, 32349).variable[0]  # Sirius
    assert not star(catalog, 37826).variable[0]  # Pollux
    assert 0.05 < catalog.variable.mean() < 0.09


def test_arrays_are_read_only(catalog):
    with pytest.raises(ValueError, match="read-only"):
        catalog.v_mag[0] = 0.0


def test_parse_small_file_and_missing_colour(tmp_path):
    lines = catalog_file().read_bytes().splitlines()
    hip = [int(line[:6]) for line in lines[:60]]
    path = tmp_path / "hip2.dat"
    path.write_bytes(b"\n".join(lines[:60]) + b"\n")
    small = catalog_from_arrays(parse_hip2(path))
    np.testing.assert_array_equal(small.hip, hip)
    assert np.isnan(small.b_v[small.hip == 45][0])  # HIP 45 has no B-V in the file
    assert small.b_v[small.hip == 1][0] == pytest.approx(0.482)


def test_parse_rejects_a_malformed_file(tmp_path):
    path = tmp_path / "hip2.dat"
    path.write_bytes(catalog_file().read_bytes()[:1000])
    with pytest.raises(InvalidInputError, match="276 bytes"):
        parse_hip2(path)


def test_missing_file_is_reported(tmp_path):
    with pytest.raises(InvalidInputError, match="does not exist"):
        load_hip2_arrays(tmp_path / "nothing.dat")


@pytest.mark.parametrize("garbage", [b"not a zip file at all", b""])
def test_corrupt_cache_is_rebuilt(tmp_path, monkeypatch, catalog, garbage):
    monkeypatch.setenv(cache.ENV_VAR, str(tmp_path))
    first = load_hip2_arrays()
    (cache_file,) = Path(tmp_path).glob(f"{CACHE_KIND}-*.npz")
    cache_file.write_bytes(garbage)
    rebuilt = load_hip2_arrays()
    np.testing.assert_array_equal(rebuilt["hip"], catalog.hip)
    np.testing.assert_array_equal(rebuilt["ra_rad"], first["ra_rad"])
    with np.load(cache_file) as npz:  # the file was rewritten and is valid again
        np.testing.assert_array_equal(npz["hip"], catalog.hip)
