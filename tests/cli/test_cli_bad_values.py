"""Values that reached the libraries unchecked (a probe of every command's options with -1, 0, nan,
inf, 1e300, 1e-300, words and wrong files): each now ends in one line naming the option and what is
valid, exit status 2. Before, they ended as "unexpected" errors (exit 3), or as a bare library message."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cli_runner import run
from startrack.io import write_fits


@pytest.fixture
def files(tmp_path):
    """A folder holding one small frame, a binary file and a FITS file where JSON is asked for."""
    (tmp_path / "frames").mkdir()
    write_fits(tmp_path / "frames" / "f0.fits", np.zeros((64, 64), np.uint16))
    (tmp_path / "binary.json").write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe")
    (tmp_path / "afile").write_text("not a folder")
    return tmp_path


@pytest.mark.parametrize("argv, words", [
    # 1e300 s of sky overflowed the Poisson draw ("zero-size array to reduction operation minimum")
    (["simulate", "--seed", 3, "--exposure-s", 1e300, "--out", "{d}/x.fits"],
     "startrack simulate: error: a pixel expects 2e+301 electrons in the exposure, more than the 1e+18"),
    (["simulate", "--seed", 3, "--prnu", 1e300, "--out", "{d}/x.fits"], "shorten the exposure or lower the aperture"),
    # the ZeroDivisionError of the streak fit, exit 3
    (["track", "{d}/frames", "--exposure-s", 1e300], "startrack track: error: --exposure-s must be 0.0001 to 3600 s"),
    # "Maximum allowed size exceeded" and "zero-size array", exit 3
    (["adcs-demo", "--duration-s", 1e300], "duration_s must hold 1 to 10,000,000 control ticks of 0.025 s"),
    (["adcs-demo", "--duration-s", 1e-300], "duration_s must hold 1 to 10,000,000 control ticks"),
    # numpy's "expected non-negative integer", exit 3
    (["adcs-demo", "--duration-s", 20, "--seed", -1], "seed must be an integer >= 0, got -1"),
    # JSONDecodeError, exit 3
    (["adcs-demo", "--duration-s", 20, "--noise-model", "{d}/binary.json"],
     "tracker noise model {d}/binary.json is not JSON text: byte 0 is not UTF-8"),
    (["adcs-demo", "--duration-s", 20, "--noise-model", "{d}/none.json"],
     "cannot read tracker noise model {d}/none.json: No such file or directory"),
    # a UnicodeDecodeError (exit 2, but the codec's words)
    (["simulate", "--rig", "{d}/binary.json", "--out", "{d}/sim"], "rig file {d}/binary.json is not JSON text"),
    # "[Errno 17] File exists: 'afile'"
    (["web", "--data-dir", "{d}/afile"], "--data-dir {d}/afile is a file; give a folder"),
])
def test_a_bad_value_is_one_line_and_exit_2(files, argv, words):
    code, out, err = run(*[str(a).format(d=files) for a in argv])
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and words.format(d=files) in err, err
    assert not (files / "x.fits").exists() and not (files / "sim").exists()


@pytest.fixture
def odd_frames(files):
    """``files`` plus a frame of NaN only and a dark frame of another size than f0.fits."""
    write_fits(files / "nan.fits", np.full((64, 64), np.nan, np.float32))
    write_fits(files / "dark32.fits", np.zeros((32, 32), np.float32))
    return files


@pytest.mark.parametrize("argv, words", [
    # the solver's own words: "give fov_deg or a camera (or use method='quads' with a FOV range)"
    (["solve", "{d}/frames/f0.fits", "--method", "pyramid"],
     "--method pyramid needs the field of view to within 5 %: give --fov-deg or --camera"),
    (["solve", "{d}/frames/f0.fits", "--method", "angle", "--fov-deg", 10, "--pixel-aspect", 0.9, 1.1],
     "--method angle needs one pixel aspect"),
    # "dark_frame must have the image's shape (64, 64), got (32, 32)": no file, a parameter's name
    (["detect", "{d}/frames/f0.fits", "--dark", "{d}/dark32.fits"],
     "--dark {d}/dark32.fits is 32 x 32 px and {d}/frames/f0.fits 64 x 64 px"),
    # the image's problem without the image's name
    (["detect", "{d}/nan.fits"], "startrack detect: error: {d}/nan.fits: image has no finite pixel"),
    (["calibrate", "{d}/nan.fits"], "startrack calibrate: error: {d}/nan.fits: image has no finite pixel"),
    # "[Errno 17] File exists", after every image was solved
    (["analyse", "histograms", "{d}/frames/f0.fits", "--out", "{d}/afile"], "--out {d}/afile is a file; give a folder"),
    # --fov-deg was silently ignored beside a camera preset
    (["availability", "--camera", "far-mst", "--fov-deg", 10], "give --camera PRESET or --fov-deg F, not both"),
])
def test_fuzzed_inputs_are_one_line_naming_the_file_or_option(odd_frames, argv, words):
    code, out, err = run(*[str(a).format(d=odd_frames) for a in argv])
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and words.format(d=odd_frames) in err, err


@pytest.mark.parametrize("argv", [
    ["solve", "{d}/frames/f0.fits", "--wcs"], ["solve", "{d}/frames/f0.fits", "--new-fits"],
    ["solve", "{d}/frames/f0.fits", "--plot"], ["solve", "{d}/frames/f0.fits", "--camera"],
    ["simulate", "--out"], ["demo", "--out"], ["track", "{d}/frames", "--out"], ["adcs-demo", "--out"],
    ["analyse", "histograms", "{d}/frames", "--out"], ["calibrate", "{d}/frames/f0.fits", "--out"],
])
def test_an_empty_name_is_refused_not_taken_as_no_option(files, argv):
    """'' was taken as the option left out (no WCS written, the default output used)."""
    code, out, err = run(*[str(a).format(d=files) for a in argv], "")
    assert code == 2 and out == "" and f"argument {argv[-1]}: expected a name, got ''" in err


@pytest.mark.parametrize("argv, words", [
    # the run went to its end, then the noise model refused "latency_s ... <= 60"
    (["adcs-demo", "--feedback", "tracker", "--duration-s", 2, "--latency-s", 1e9], "--latency-s must be 0 to 30 s"),
    # --square-mm without --checkerboard was ignored
    (["calibrate", "{d}/frames/f0.fits", "--square-mm", 30], "give it with --checkerboard"),
    # argparse took a negative number in exponent notation for an option: "expected one argument"
    (["solve", "{d}/frames/f0.fits", "--epoch", "-1e9"], "--epoch must be a Julian year such as 2025.5"),
    (["warm-up", "--fov-range-deg", "-1e3", 5], "--fov-range-deg must be a field of view between 0.5 and 150"),
    # beyond float64, or -inf: "expected one argument" too, where +1e400 was named
    (["simulate", "--epoch", "-1e400", "--out", "{d}/x.fits"], "--epoch must be a finite number, got -inf"),
    (["simulate", "--epoch", "-inf", "--out", "{d}/x.fits"], "--epoch must be a finite number, got -inf"),
])
def test_options_checked_before_the_work(files, argv, words):
    code, out, err = run(*[str(a).format(d=files) for a in argv])
    assert code == 2 and out == "" and err.count("\n") == 1 and words in err, err


def test_every_negative_number_is_a_value_of_its_option():
    """argparse took "-1e9", "-1e400" and "-inf" for unknown options ("expected one argument");
    startrack's parsers read them as values, as typed, and leave options alone."""
    from startrack.cli._parser import CommandParser

    parser = CommandParser(prog="probe")
    parser.add_argument("--x", type=float)
    parser.add_argument("--name")
    for text in ("-1e9", "-2.5E-3", "-1e-300", "-.5e2", "-5", "-0.25", "-inf", "-Infinity", "-1e400"):
        assert parser.parse_args(["--x", text]).x == float(text)
    assert parser.parse_args(["--name", "-inf"]).name == "-inf"
    assert math.isnan(parser.parse_args(["--x", "-nan"]).x)
    with pytest.raises(SystemExit):  # an unknown option is still one
        parser.parse_args(["--x", "1", "-e9"])


@pytest.mark.parametrize("argv, words", [
    # ignored without --rig, or for one frame
    (["simulate", "--time", "2025-03-20T12:00:00", "--out", "{d}/x.fits"], "give --rig, or leave them out"),
    (["simulate", "--altitude-km", 700, "--out", "{d}/x.fits"], "give --rig, or leave them out"),
    (["simulate", "--format", "png", "--out", "{d}/x.fits"], "--format sets the files of a sequence"),
    # empty figures and exit 0 when no image could be read
    (["analyse", "histograms", "{d}/frames/f0.fits", "--max-pixels", 1, "--out", "{d}/an"],
     "no image could be read (1 tried; the first: {d}/frames/f0.fits: image is 64 x 64"),
])
def test_options_that_did_nothing_are_refused(files, argv, words):
    code, out, err = run(*[str(a).format(d=files) for a in argv])
    assert code == 2 and out == "" and words.format(d=files) in err.splitlines()[-1], err
    assert not (files / "x.fits").exists() and not (files / "an").exists()
