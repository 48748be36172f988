"""Ground-based photos: time from headers, sites, alt/az of the pointing (against astropy),
refraction applied in the horizon frame, RAW mosaic reduction."""

import math
import warnings

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import AltAz, EarthLocation, SkyCoord
from astropy.time import Time
from astropy.utils import iers

from startrack.calibrate._ground import (
    altaz_from_vectors,
    pointing_altaz,
    refract_icrs,
    rotation_enu_from_icrs,
    time_from_header,
    unrefract_icrs,
)
from startrack.calibrate._sites import BUILTIN_SITES, Site, delete_site, get_site, load_sites, save_site
from startrack.errors import InvalidInputError
from startrack.frames import angle_between, radec_to_vector, rotation_from_radec_roll
from startrack.io._raw import bayer_cells, full_resolution_xy
from startrack.units import ARCSEC, DEG

SITE = BUILTIN_SITES["logan-ut-2012"]
TIME = Time("2012-10-05T04:30:00", scale="utc")  # Fowler 2013's RS1 night


def test_fits_and_exif_times():
    assert time_from_header({"DATE-OBS": "2012-10-05T04:30:00", "EXPTIME": 10.0}).isot == "2012-10-05T04:30:05.000"
    assert time_from_header({"DATE-OBS": "2012-10-05", "TIME-OBS": "04:30:00"}, mid_exposure=False).isot \
        == "2012-10-05T04:30:00.000"
    exif = {"DateTimeOriginal": "2012:10:04 22:30:00", "ExposureTime": 2.0}
    assert time_from_header(exif, utc_offset_hours=-6).isot == "2012-10-05T04:30:01.000"
    with_zone = {**exif, "OffsetTimeOriginal": "-06:00", "SubsecTimeOriginal": "25"}
    assert time_from_header(with_zone, mid_exposure=False).isot == "2012-10-05T04:30:00.250"
    with pytest.raises(InvalidInputError, match="utc_offset_hours"):
        time_from_header(exif)
    with pytest.raises(InvalidInputError, match="DATE-OBS"):
        time_from_header({})


def test_sites_are_saved_by_name(tmp_path, monkeypatch):
    monkeypatch.setenv("STARTRACK_CONFIG_DIR", str(tmp_path))
    assert "moab-ut" in load_sites()
    save_site(Site("backyard", 52.1, 4.3, 5.0, temperature_c=3.0, pressure_kpa=102.0))
    assert get_site("backyard").pressure == 102.0
    assert (tmp_path / "sites.json").is_file()
    delete_site("backyard")
    with pytest.raises(InvalidInputError, match="unknown site"):
        get_site("backyard")
    assert Site("x", 0.0, 0.0, 1500.0).pressure == pytest.approx(84.9, abs=0.5)
    with pytest.raises(InvalidInputError, match="latitude_deg"):
        Site("bad", 95.0, 0.0)


def _astropy_altaz(ra_deg, dec_deg):
    loc = EarthLocation(lat=SITE.latitude_deg * u.deg, lon=SITE.longitude_deg * u.deg, height=SITE.height_m * u.m)
    with iers.conf.set_temp("auto_download", False), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        aa = SkyCoord(ra=ra_deg * u.deg, dec=dec_deg * u.deg).transform_to(AltAz(obstime=TIME, location=loc))
    return aa.alt.rad, aa.az.rad


def test_horizon_frame_agrees_with_astropy():
    """astropy's AltAz (no refraction) of an ICRS direction vs our GCRS-apparent -> ENU; astropy
    applies aberration inside the transform, so we feed it the aberrated direction's ICRS twin."""
    from startrack.calibrate._apparent import aberrate, earth_state

    ra, dec = np.array([10.0, 120.0, 250.0, 300.0]), np.array([20.0, 60.0, -5.0, 45.0])
    alt, az = _astropy_altaz(ra, dec)
    apparent = aberrate(radec_to_vector(ra * DEG, dec * DEG), earth_state(TIME).velocity_m_s)
    ours_alt, ours_az = altaz_from_vectors(rotation_enu_from_icrs(TIME, SITE).apply(apparent))
    up = alt > 0
    ours = np.stack([np.cos(ours_alt) * np.sin(ours_az), np.cos(ours_alt) * np.cos(ours_az), np.sin(ours_alt)], -1)
    ref = np.stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)], -1)
    assert np.max(angle_between(ours[up], ref[up])) < 1.0 * ARCSEC


def test_pointing_altaz_and_refraction_direction():
    rot = rotation_from_radec_roll(300.0 * DEG, 45.0 * DEG, 0.0)
    alt_true, az = pointing_altaz(rot, TIME, SITE, refracted=False)
    alt_app, az2 = pointing_altaz(rot, TIME, SITE)
    assert alt_app > alt_true and az2 == pytest.approx(az, abs=1e-9)
    ref_alt, ref_az = _astropy_altaz(300.0, 45.0)
    assert alt_true == pytest.approx(math.degrees(ref_alt), abs=0.01)
    stars = radec_to_vector(np.radians([300.0, 310.0]), np.radians([45.0, 30.0]))
    seen = refract_icrs(stars, TIME, SITE)
    enu = rotation_enu_from_icrs(TIME, SITE)
    assert np.all(altaz_from_vectors(enu.apply(seen))[0] > altaz_from_vectors(enu.apply(stars))[0])
    np.testing.assert_allclose(unrefract_icrs(seen, TIME, SITE), stars, atol=1e-10)
    assert np.all(angle_between(seen, stars) < 5 * 60 * ARCSEC)


def test_bayer_cells_sum_and_channels():
    mosaic = np.arange(16).reshape(4, 4)
    rggb = np.array([[0, 1], [3, 2]])
    np.testing.assert_array_equal(bayer_cells(mosaic, rggb), [[0 + 1 + 4 + 5, 2 + 3 + 6 + 7],
                                                              [8 + 9 + 12 + 13, 10 + 11 + 14 + 15]])
    np.testing.assert_array_equal(bayer_cells(mosaic, rggb, "g"), [[1 + 4, 3 + 6], [9 + 12, 11 + 14]])
    np.testing.assert_array_equal(bayer_cells(mosaic, rggb, "R"), [[0, 2], [8, 10]])
    assert full_resolution_xy(0.0, 1.0) == (0.5, 2.5)
    with pytest.raises(InvalidInputError, match="channel"):
        bayer_cells(mosaic, rggb, "alpha")
