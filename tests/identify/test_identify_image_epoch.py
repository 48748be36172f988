"""The catalog epoch of a solve: given, from the image header, or J2000.0; and it is used."""

import numpy as np
import pytest
from astropy.time import Time

from startrack import Camera, solve_image
from startrack.errors import InvalidInputError
from startrack.frames import rotation_from_radec_roll
from startrack.identify._image_epoch import epoch_from_header, epoch_jyear, parse_utc, resolve_epoch
from startrack.io import Image
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import DEG

HEADERS = {
    "FITS DATE-OBS": ({"DATE-OBS": "2024-07-02T00:00:00"}, 2024.5, "DATE-OBS"),
    "FITS date and TIME-OBS": ({"DATE-OBS": "2024-07-02", "TIME-OBS": "12:00:00"}, 2024.5014, "DATE-OBS"),
    "FITS MJD-OBS": ({"MJD-OBS": 60493.0}, 2024.5, "MJD-OBS"),
    "our simulator's CATEPOCH": ({"CATEPOCH": 2031.25, "DATE-OBS": "2024-07-02T00:00:00"}, 2031.25, "CATEPOCH"),
    "EXIF with its zone": ({"DateTimeOriginal": "2024:07:02 02:00:00", "OffsetTimeOriginal": "+02:00"}, 2024.5,
                           "DateTimeOriginal"),
    "EXIF without a zone (taken as UTC)": ({"DateTimeOriginal": "2024:07:02 00:00:00"}, 2024.5, "DateTimeOriginal"),
}


@pytest.mark.parametrize(("header", "jyear", "source"), HEADERS.values(), ids=HEADERS.keys())
def test_the_header_states_the_epoch(header, jyear, source):
    epoch = epoch_from_header(header)
    assert epoch.source == source
    assert epoch.jyear == pytest.approx(jyear, abs=2e-3)  # a day is 0.0027 yr


def test_a_given_epoch_wins_and_nothing_means_j2000():
    assert resolve_epoch(2025.5, {"DATE-OBS": "2010-01-01T00:00:00"}).jyear == 2025.5
    assert resolve_epoch(Time("2010-01-01T12:00:00", scale="utc")).source == "given"
    assert resolve_epoch(None, {"EXPTIME": 2.0}).jyear == 2000.0
    assert resolve_epoch(None, None).source == "default"


def test_an_unset_camera_clock_is_passed_over():
    assert epoch_from_header({"DateTimeOriginal": "0000:00:00 00:00:00"}) is None
    assert epoch_from_header({"DateTimeOriginal": "garbage"}) is None


@pytest.mark.parametrize(("header", "card"), [({"DATE-OBS": "yesterday"}, "DATE-OBS"),
                                              ({"MJD-OBS": "soon"}, "MJD-OBS"),
                                              ({"MJD-OBS": float("nan")}, "MJD-OBS"),
                                              ({"MJD-OBS": 1e12}, "MJD-OBS"),
                                              ({"CATEPOCH": 1e9}, "epoch")])
def test_a_fits_time_that_cannot_be_read_is_refused_naming_the_card(header, card):
    with pytest.raises(InvalidInputError, match=card):
        epoch_from_header(header)
    assert resolve_epoch(2020.0, header).jyear == 2020.0  # an epoch given overrides the header


@pytest.mark.parametrize("bad", ["2025", True, -4, float("inf"), np.array([2020.0, 2021.0]), "soon"])
def test_bad_epochs_are_refused(bad):
    with pytest.raises(InvalidInputError, match="epoch"):
        epoch_jyear(bad)


@pytest.mark.parametrize("text", ["garbage", "2024-13-45", "0500-01-01T00:00:00", ""])
def test_times_are_parsed_or_refused(text):
    with pytest.raises(InvalidInputError, match="--time"):
        parse_utc(text, "--time")


def test_solve_image_uses_and_reports_the_image_time():
    """A frame rendered at the 2031.25 catalog (its stars moved by proper motion since J2000):
    solved from its header the matched catalog vectors are those of 2031.25 and the solution
    says so; an explicit epoch overrides the header; an array has no header (J2000.0)."""
    camera = Camera.from_fov(1024, 1024, 15.0)
    truth = rotation_from_radec_roll(101.3 * DEG, -16.7 * DEG, 10 * DEG)  # Sirius, 1.3 arcsec a year
    sim = simulate_frame(camera, truth, max_mag=7.5, sensor=get_sensor_preset("generic-cmos"), epoch_jyear=2031.25,
                         rng=5)
    image = Image(sim.image, header={"DATE-OBS": "2031-04-02T00:00:00"})
    solution = solve_image(image, fov_deg=15.0)
    assert solution.solved, solution.reason
    assert (solution.epoch_source, solution.epoch_jyear) == ("DATE-OBS", pytest.approx(2031.25, abs=3e-3))
    from startrack.catalog import load_catalog

    catalog = load_catalog()
    rows = np.searchsorted(catalog.hip, solution.matches.hip)
    np.testing.assert_allclose(solution.matches.cat_vectors, catalog.take(rows).vectors(solution.epoch_jyear),
                               atol=1e-12)
    forced = solve_image(image, fov_deg=15.0, epoch=2000.0)
    assert (forced.epoch_source, forced.epoch_jyear) == ("given", 2000.0)
    plain = solve_image(sim.image, fov_deg=15.0)
    assert (plain.epoch_source, plain.epoch_jyear) == ("default", 2000.0)
