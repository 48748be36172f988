"""Frames and their truth on disk (FITS cards, WCS, tables, JSON, sequence index) and the
``startrack simulate`` options for motion, noise, detector effects and sequences."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from astropy.io import fits
from astropy.time import Time
from astropy.wcs import WCS

from cli_runner import run
from startrack.camera import Camera
from startrack.frames import angle_between, radec_to_vector
from startrack.io._truth_files import index_row, write_frame, write_index
from startrack.simulate import FrameTiming, get_sensor_preset, random_attitude, save_profile, simulate_frame, tumble
from startrack.units import DEG, PIXEL


@pytest.fixture(scope="module")
def streaked():
    camera = Camera.from_fov(320, 240, 12.0, name="test")
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.3)
    return simulate_frame(camera, random_attitude(21), max_mag=7.5, sensor=sensor, rng=3,
                          rate_rad_s=(0.2 * DEG, -0.4 * DEG, 0.1 * DEG),
                          timing=FrameTiming(epoch=Time("2026-06-01T03:00:00", scale="utc")))


def test_fits_holds_the_camera_sensor_time_and_a_wcs_that_finds_the_stars(streaked, tmp_path):
    path = write_frame(tmp_path / "frame.fits", streaked.image, streaked.truth)[0]
    with fits.open(path) as hdus:
        header = hdus[0].header
        table = hdus["TRUTH"].data
        cards = {"FOCALPX", "CX0", "GAIN", "RDNOISE", "BITDEPTH", "RATE_Y", "DATE-OBS", "DATE-AVG", "NOISE"}
        assert cards <= set(header)
        assert header["RATE_Y"] == pytest.approx(-0.4) and header["DATE-AVG"].startswith("2026-06-01T03:00:00")
        assert header["DATE-OBS"].startswith("2026-06-01T02:59:59.85")
        wcs = WCS(header)
        truth = streaked.truth
        inside = truth.inside()
        assert len(table) == inside.sum() > 5
        np.testing.assert_allclose(table["x_start"], truth.x_start[inside])
        world = wcs.pixel_to_world(table["x"], table["y"])
        found = radec_to_vector(world.ra.rad, world.dec.rad)
        err = angle_between(found, truth.vectors_icrs[inside])
        assert err.max() < 0.01 * PIXEL / truth.camera.fx


def test_png_sidecar_has_the_streak_end_points(streaked, tmp_path):
    files = write_frame(tmp_path / "frame.png", streaked.image, streaked.truth)
    data = json.loads(files[1].read_text())
    star = data["stars"][0]
    assert {"x_start", "y_start", "x_end", "y_end", "b_v"} <= set(star)
    assert data["rate_deg_s"] == pytest.approx([0.2, -0.4, 0.1])
    assert data["time_mid"].startswith("2026-06-01T03:00:00") and data["sensor"]["name"] == "generic-cmos"
    length = np.hypot(star["x_end"] - star["x_start"], star["y_end"] - star["y_start"])
    assert length == pytest.approx(np.radians(0.3 * np.hypot(0.2, 0.4)) * 320 / (2 * np.tan(np.radians(6))),
                                   rel=0.05)


def test_sequence_index_rows(streaked, tmp_path):
    row = index_row(streaked.truth, tmp_path / "frame_00000.fits")
    path = write_index(tmp_path / "frames.csv", [row, row])
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 and rows[0]["file"] == "frame_00000.fits"
    assert float(rows[0]["rate_y_deg_s"]) == pytest.approx(-0.4)


# ---------------------------------------------------------------- the command line
def test_cli_one_streaked_frame_with_every_effect(tmp_path):
    out = tmp_path / "one.fits"
    code, text, err = run("simulate", "--seed", 5, "--fov-deg", 10, "--width", 128, "--height", 96,
                          "--rate-deg-s", 0.5, 0, 0, "--exposure-s", 0.4, "--prnu", 0.01, "--dsnu", 0.2,
                          "--hot-pixels", 1e-3, "--dead-pixels", 1e-3, "--zodiacal", "--stray-e-s", 5,
                          "--blooming", "--line-time-s", 1e-5, "--out", out, "--json")
    assert code == 0, err
    truth = json.loads(text)
    assert truth["rate_deg_s"] == pytest.approx([0.5, 0.0, 0.0]) and truth["line_time_s"] == 1e-5
    assert out.is_file()


def test_cli_noise_switches_give_the_expected_image(tmp_path):
    out = tmp_path / "quiet.fits"
    code, _, err = run("simulate", "--seed", 5, "--fov-deg", 10, "--width", 64, "--height", 64, "--no-shot",
                       "--no-read", "--no-dark", "--no-bias", "--no-quantize", "--out", out)
    assert code == 0, err
    with fits.open(out) as hdus:
        data = hdus[0].data
        assert data.dtype.kind == "f" and data.min() == 0.0  # the expectation: stars only


def test_cli_sequence_writes_frames_and_an_index_with_a_progress_bar(tmp_path):
    folder = tmp_path / "seq"
    code, text, err = run("simulate", "--seed", 2, "--fov-deg", 10, "--width", 64, "--height", 48, "--frames", 3,
                          "--rate-deg-s", 0, 0, 2, "--exposure-s", 0.1, "--frame-rate-hz", 5, "--format", "png",
                          "--out", folder)
    assert code == 0, err
    assert "frames: 3/3" in err  # stderr is not a terminal here: plain progress lines
    with (folder / "frames.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [r["file"] for r in rows] == [f"frame_0000{k}.png" for k in range(3)]
    assert float(rows[1]["t_mid_s"]) - float(rows[0]["t_mid_s"]) == pytest.approx(0.2)
    # turning about +z (the boresight) brings "up" towards the west: the roll grows
    assert float(rows[2]["roll_deg"]) - float(rows[0]["roll_deg"]) == pytest.approx(0.8, abs=1e-6)
    assert (folder / "frame_00002.truth.json").is_file()


def test_cli_sequence_from_a_recorded_profile(tmp_path):
    profile = save_profile(tmp_path / "p.csv", tumble(random_attitude(1), [1, 0, 0], 1 * DEG), np.arange(0, 3.0, 0.5))
    code, text, err = run("simulate", "--seed", 2, "--fov-deg", 10, "--width", 64, "--height", 48, "--frames", 2,
                          "--profile", profile, "--exposure-s", 0.1, "--out", tmp_path / "rec", "--json")
    assert code == 0, err
    assert json.loads(text)["frames"] == 2 and (tmp_path / "rec" / "frame_00001.fits").is_file()


@pytest.mark.parametrize(("options", "words"), [
    (("--frames", 2, "--out", "x.fits"), ("folder",)),
    (("--frames", 0), ("--frames",)),
    (("--prnu", -0.1, "--out", "x.fits"), ("prnu_rms",)),
    (("--rate-deg-s", 1, 2, "nan", "--out", "x.fits"), ("--rate-deg-s",)),
    (("--sky-mag-arcsec2", 21, "--zodiacal", "--out", "x.fits"), ("--zodiacal",)),
    (("--frames", 2, "--frame-rate-hz", 100, "--exposure-s", 0.1, "--out", "f"), ("frame period",)),
])
def test_cli_bad_render_options_fail_cleanly(tmp_path, options, words):
    options = [tmp_path / o if o in ("x.fits", "f") else o for o in options]
    code, out, err = run("simulate", "--seed", 1, "--width", 32, "--height", 32, *options)
    assert code == 2 and out == "", err
    line = err.strip().splitlines()[-1]
    assert line.startswith("startrack simulate: error:") and all(w in line for w in words), line
