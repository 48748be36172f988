"""Refusals of ``startrack simulate --rig`` / ``simulate`` / ``demo`` found by fuzzing: every one exits 2
with one line ``startrack <cmd>: error: ...`` that names the JSON key or the option and what is valid,
no traceback, and no output folder left behind.

Each case is refused before anything is rendered, so the tests are fast.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

from cli_runner import run
from startrack.cli import main
from startrack.errors import OutputError

GOOD_CAMERA = {"width": 32, "height": 32, "fx": 150.0}
IDENTITY = {"qx": 0, "qy": 0, "qz": 0, "qw": 1}
LEAKS = ("Traceback", "__init__", "argument after **", "could not convert", "positional argument",
         "unexpected keyword", "sys.set_int_max_str_digits", "a fault of startrack's")


def assert_misuse(result: tuple[int, str, str], command: str, *words: str) -> str:
    """Exit 2, nothing on stdout, one stderr line naming the command and holding ``words``, no internals."""
    code, out, err = result
    assert code == 2, err
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith(f"startrack {command}: error: "), line
    assert all(word in line for word in words), line
    assert not any(leak in line for leak in LEAKS), line
    return line


def write_rig(folder: Path, camera=None, text: str | None = None, **head) -> Path:
    """A one-head rig file (head ``a``) with ``camera`` and the extra head keys, or the raw ``text``."""
    path = folder / "rig.json"
    entry = {"name": "a", "camera": GOOD_CAMERA if camera is None else camera, "rot_cam_from_body": IDENTITY, **head}
    path.write_text(text if text is not None else json.dumps({"heads": [entry]}))
    return path


def simulate_rig(folder: Path, rig: Path, *options) -> tuple[int, str, str]:
    return run("simulate", "--rig", rig, "--seed", 1, "--no-noise", "--out", folder / "out", *options)


# --- 1. image sizes against --max-pixels -------------------------------------------------------

def test_a_rig_camera_wider_than_any_image_is_refused_by_its_key(tmp_path):
    rig = write_rig(tmp_path, {"width": 2**70, "height": 64, "fx": 300.0})
    assert_misuse(simulate_rig(tmp_path, rig), "simulate", "head 'a'", "camera width", str(2**70),
                  "JSON integer", "2,147,483,647")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("size", "options"), [
    (100_000, ()),  # 74.5 GiB was allocated (and failed late as out of memory)
    (2_000, ("--max-pixels", 1_500_000)),
])
def test_a_rig_camera_over_the_pixel_limit_is_refused_before_rendering(tmp_path, size, options):
    rig = write_rig(tmp_path, {"width": size, "height": size, "fx": 3000.0})
    assert_misuse(simulate_rig(tmp_path, rig, *options), "simulate", "head 'a'",
                  f"camera width {size} x height {size}", "over the limit", "--max-pixels")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("size", "options"), [
    (100_000, ()),
    (3_000, ("--max-pixels", 2_000_000)),  # demo had no --max-pixels
])
def test_demo_checks_its_size_against_max_pixels(tmp_path, size, options):
    out = tmp_path / "demo"
    result = run("demo", "--width", size, "--height", size, "--seed", 1, "--out", out, *options)
    assert_misuse(result, "demo", f"--width {size} --height {size}", "over the limit", "--max-pixels")
    assert not out.exists()


# --- 2. rig JSON errors name the key and what is valid ------------------------------------------

@pytest.mark.parametrize(("camera", "head", "words"), [
    ({}, {}, ("camera is missing width, height, fx", "valid keys")),
    (None, {"exclusion": "x"}, ("exclusion must be an object", "sun_deg, earth_limb_deg, moon_deg")),
    (None, {"exclusion": {"sun_deg": "x"}}, ("exclusion sun_deg must be a number",)),
    (None, {"exclusion": {"sun": 30}}, ("unknown exclusion keys ['sun']", "valid: sun_deg")),
    (None, {"psf": "x"}, ("psf must be an object", "sigma_major_px")),
    (None, {"psf": {"sigma_major_px": 2.0}}, ("psf is missing sigma_minor_px",)),
    (None, {"rot_cam_from_body": {**IDENTITY, "qx": "a"}}, ("rot_cam_from_body qx must be a number", "'a'")),
    ({**GOOD_CAMERA, "width": 1e9}, {}, ("camera width", "1000000000.0", "not a JSON integer", "valid")),
    ({**GOOD_CAMERA, "height": 2.5}, {}, ("camera height", "not a whole number", "valid")),
    ({**GOOD_CAMERA, "width": "wide"}, {}, ("camera width", "not a number", "valid")),
])
def test_rig_json_errors_name_the_key(tmp_path, camera, head, words):
    rig = write_rig(tmp_path, camera, **head)
    assert_misuse(simulate_rig(tmp_path, rig), "simulate", "rig file", "head 'a'", *words)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("text", "words"), [
    ('{"heads": [{"name": "a", "camera": {"width": ' + "9" * 5000 + ', "height": 64, "fx": 300.0}, '
     '"rot_cam_from_body": {"qx": 0, "qy": 0, "qz": 0, "qw": 1}}]}', ("integer of more than", "digits")),
    ("[" * 100_000 + "]" * 100_000, ("too deeply",)),
])
def test_rig_json_that_python_cannot_decode_is_bad_input(tmp_path, text, words):
    rig = write_rig(tmp_path, text=text)
    assert_misuse(simulate_rig(tmp_path, rig), "simulate", "rig file", *words)


# --- 3. no empty output folder after a failure --------------------------------------------------

def test_a_sequence_whose_exposure_does_not_fit_leaves_no_folder(tmp_path):
    out = tmp_path / "seq"
    result = run("simulate", "--width", 256, "--height", 256, "--frames", 3, "--frame-rate-hz", 1e300,
                 "--seed", 1, "--out", out)
    assert_misuse(result, "simulate", "--frame-rate-hz", "frame period", "valid: at most")
    assert not out.exists()


def test_a_sequence_that_fails_before_writing_removes_the_folder_it_made(tmp_path, monkeypatch):
    def full_disk(*args, **kwargs):
        raise OutputError("cannot write the frame: no space left on device")

    monkeypatch.setattr("startrack.cli._simulate_cmd.write_frame", full_disk)
    out = tmp_path / "new" / "seq"
    result = run("simulate", "--width", 32, "--height", 32, "--frames", 2, "--seed", 1, "--no-noise",
                 "--max-mag", 3, "--out", out, "--json")
    assert_misuse(result, "simulate", "no space left")
    assert not (tmp_path / "new").exists()


# --- 4. --frame-rate-hz is checked whatever --frames is -----------------------------------------

@pytest.mark.parametrize("frames", [1, 3])
@pytest.mark.parametrize("rate", ["0", "-1", "5e-324"])
def test_a_frame_rate_that_is_not_positive_is_refused_for_one_frame_too(tmp_path, frames, rate):
    out = tmp_path / ("one.fits" if frames == 1 else "seq")
    result = run("simulate", "--width", 32, "--height", 32, "--frames", frames, "--frame-rate-hz", rate,
                 "--seed", 1, "--out", out)
    assert_misuse(result, "simulate", "--frame-rate-hz must be a positive number")
    assert not out.exists()


def test_a_single_frame_longer_than_its_frame_period_is_refused(tmp_path):
    out = tmp_path / "one.fits"
    result = run("simulate", "--width", 32, "--height", 32, "--exposure-s", 0.5, "--frame-rate-hz", 10,
                 "--seed", 1, "--out", out)
    assert_misuse(result, "simulate", "--frame-rate-hz 10", "frame period", "at most 2 Hz")
    assert not out.exists()


def test_a_small_rig_renders_under_a_small_pixel_limit(tmp_path):
    """The limit of --width and --height (1024 x 1024 by default) was checked for a rig too, whose
    heads have sizes of their own: a 60 x 40 px head under --max-pixels 5000 was refused."""
    rig = tmp_path / "small.json"
    rig.write_text('{"heads": [{"name": "a", "camera": {"width": 60, "height": 40, "fx": 300.0}, '
                   '"rot_cam_from_body": {"qx": 0, "qy": 0, "qz": 0, "qw": 1}}]}')
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["simulate", "--rig", str(rig), "--max-pixels", "5000", "--out", str(tmp_path / "sim")])
    assert code == 0, err.getvalue()
    assert (tmp_path / "sim").is_dir()
