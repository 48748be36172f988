"""The command line and hostile input (issue 17, part A): outputs over inputs, devices and pipes,
``track`` past bad frames, accepted nonsense, memory, signals, warnings. Each test names what
happened before. Commands run in-process (``startrack.cli.main``) except where a real
process is the point (a pipe, a signal, a memory limit, a warning printed to a terminal log)."""

from __future__ import annotations

import contextlib
import csv
import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cli_runner import run
from startrack.camera import Camera
from startrack.cli import main
from startrack.cli._progress import ensure_database
from startrack.cli._run_context import DUBIOUS_YEAR
from startrack.frames import rotation_from_radec_roll
from startrack.io import write_fits, write_png
from startrack.io._truth_files import write_frame
from startrack.io._wcs import read_wcs
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import DEG

STARTRACK = [sys.executable, "-m", "startrack"]
SENSOR = get_sensor_preset("generic-cmos")


def assert_misuse(result: tuple[int, str, str], command: str, *words: str) -> str:
    """Exit 2, nothing on stdout, one stderr line ``startrack <command>: error: ...`` with the words."""
    code, out, err = result
    assert code == 2 and out == "", err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"startrack {command}: error: "), err
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module", autouse=True)
def _database_loaded():
    with contextlib.redirect_stderr(io.StringIO()):
        ensure_database()


@pytest.fixture(scope="module")
def sequence(tmp_path_factory) -> Path:
    """Three 256 x 256 frames of a 15 deg camera turning slowly, a garbage frame between them, and a
    128 x 128 frame at the end."""
    folder = tmp_path_factory.mktemp("seq")
    camera = Camera.from_fov(256, 256, 15.0)
    for k in range(3):
        rot = rotation_from_radec_roll((80.0 + 0.05 * k) * DEG, 20.0 * DEG, 0.0)
        sim = simulate_frame(camera, rot, max_mag=7.0, rng=k, sensor=SENSOR)
        write_frame(folder / f"frame_{k:05d}.fits", sim.image, sim.truth)
    (folder / "frame_00001b.fits").write_bytes(b"SIMPLE  = garbage")
    small = simulate_frame(Camera.from_fov(128, 128, 15.0), rotation_from_radec_roll(80 * DEG, 20 * DEG, 0.0), rng=9,
                           sensor=SENSOR)
    write_fits(folder / "frame_00003.fits", small.image)
    return folder


def _rows(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(text)))


# --- track ------------------------------------------------------------------------------------
def test_track_goes_past_a_garbage_frame_and_a_smaller_frame_naming_each(sequence, tmp_path):
    """Before: the garbage frame aborted the run with exit 2 and no CSV (the message glued to the
    progress bar); a frame of another size gave 'star 0 lies outside the 256 x 256 image' without
    naming the file, or a silent no_match."""
    out = tmp_path / "track.csv"
    code, stdout, err = run("track", sequence, "--fov-deg", 15, "--out", out)
    assert code == 1, err
    rows = _rows(out.read_text())
    assert [r["file"] for r in rows] == ["frame_00000.fits", "frame_00001.fits", "frame_00001b.fits",
                                         "frame_00002.fits", "frame_00003.fits"]
    assert [r["status"] for r in rows] == ["ok", "ok", "error", "ok", "error"]
    assert "frame_00001b.fits" in rows[2]["reason"] and "not a readable FITS file" in rows[2]["reason"]
    assert "frame_00003.fits: frame is 128 x 128 px but the sequence's frames are 256 x 256 px" in rows[4]["reason"]
    assert rows[3]["mode"] == "tracking"
    assert "3 of 5 frames have an attitude; 2 could not be used" in stdout
    assert [p.name for p in tmp_path.iterdir()] == ["track.csv"]


def test_track_refuses_to_write_over_an_input_frame_before_any_work(sequence):
    """Before: ``track seq --out seq/frame_00001.fits`` overwrote an input frame with the CSV."""
    frame = sequence / "frame_00001.fits"
    before = frame.read_bytes()
    assert_misuse(run("track", sequence, "--out", frame), "track", "frame_00001.fits", "one of the inputs")
    assert frame.read_bytes() == before


@pytest.mark.parametrize(("value", "words"), [("inf", ("--frame-interval-s", "finite")),
                                              ("nan", ("--frame-interval-s", "nan")),
                                              ("0", ("--frame-interval-s", "positive"))])
def test_track_refuses_a_frame_interval_that_is_not_a_positive_finite_time(sequence, tmp_path, value, words):
    """Before: ``--frame-interval-s inf`` was accepted (every t_s after the first was inf or nan)."""
    assert_misuse(run("track", sequence, "--frame-interval-s", value, "--out", tmp_path / "t.csv"), "track", *words)


def test_track_pipes_its_csv_through_dev_stdout_and_dash(sequence, tmp_path):
    """Before: ``--out /dev/stdout`` was replaced by a regular file (as root: the device node)
    and nothing reached the pipe; ``-`` made a file named "-"."""
    one = tmp_path / "one"
    one.mkdir()
    (one / "frame_00000.fits").symlink_to(sequence / "frame_00000.fits")
    proc = subprocess.run([*STARTRACK, "track", str(one), "--fov-deg", "15", "--out", "/dev/stdout"],
                          capture_output=True, text=True, timeout=300)
    in_process = run("track", one, "--fov-deg", 15, "--out", "-")
    for code, stdout, err in ((proc.returncode, proc.stdout, proc.stderr), in_process):
        assert code == 0, err
        rows = _rows(stdout)
        assert len(rows) == 1 and rows[0]["status"] == "ok" and rows[0]["file"] == "frame_00000.fits"
        assert "1 of 1 frames have an attitude; wrote" in err
    assert [p.name for p in tmp_path.iterdir()] == ["one"]


# --- solve, simulate, availability ---------------------------------------------------------------
def test_solve_refuses_to_write_the_wcs_over_its_image(tmp_path):
    """Before: ``solve img.fits --wcs img.fits`` turned the image into a 5,760-byte header (exit 0)."""
    camera = Camera.from_fov(512, 512, 15.0)
    sim = simulate_frame(camera, rotation_from_radec_roll(80 * DEG, 20 * DEG, 0.3), max_mag=7.5, rng=1, sensor=SENSOR)
    image = tmp_path / "img.png"
    write_png(image, np.clip(sim.image, 0, 65535).astype(np.uint16))
    before = image.read_bytes()
    assert_misuse(run("solve", image, "--fov-deg", 15, "--wcs", image), "solve", "img.png", "one of the inputs")
    assert image.read_bytes() == before
    code, _, err = run("solve", image, "--fov-deg", 15, "--wcs", tmp_path / "img.wcs")
    assert code == 0, err
    assert read_wcs(tmp_path / "img.wcs").pixel_shape == (512, 512)


@pytest.mark.parametrize(("argv", "command", "words"), [
    (("solve", "any.fits", "--time", "garbage"), "solve", ("--time", "ISO 8601", "'garbage'")),
    (("availability", "--fov-deg", 10, "--max-mag", "nan"), "availability", ("--max-mag", "finite")),
    (("availability", "--fov-deg", "inf"), "availability", ("--fov-deg", "finite")),
    (("simulate", "--width", 1_000_000_000, "--out", "x.fits"), "simulate", ("--width 1000000000", "--max-pixels")),
    (("simulate", "--psf-sigma-px", "1e6", "--out", "x.fits"), "simulate", ("--psf-sigma-px", "at most 20 px")),
    (("simulate", "--stray-e-s", "1e30", "--out", "x.fits"), "simulate", ("--stray-e-s", "valid: 0 to 1e+09")),
    (("simulate", "--sky-mag-arcsec2=-11", "--out", "x.fits"), "simulate",
     ("--sky-mag-arcsec2 -11", "at most 1e+09 e-", "mag per arcsec^2 or fainter")),
    (("simulate", "--rate-deg-s", "1e6", 0, 0, "--out", "x.fits"), "simulate", ("--rate-deg-s", "at most 10 deg")),
    (("simulate", "--exposure-s", "nan", "--out", "x.fits"), "simulate", ("--exposure-s", "finite")),
])
def test_nonsense_is_refused_before_any_work(tmp_path, monkeypatch, argv, command, words):
    """Before: ``--time garbage`` without a site, ``--max-mag nan`` and ``--fov-deg inf`` were
    accepted; the simulator sizes ended in a MemoryError traceback (exit 1) or an error that named
    no option ('radius_rad must be in [0, pi] radians'); a sky of -11 mag per arcsec^2 took 7 GB."""
    monkeypatch.chdir(tmp_path)
    assert_misuse(run(*argv), command, *words)
    assert list(tmp_path.iterdir()) == []


def test_a_memory_error_is_a_one_line_exit_2(tmp_path):
    """Before: a MemoryError ended in a traceback with exit 1 (the code for 'not solved'). The
    process gets 2.5 GiB of address space and asks for a 20,000 x 20,000 frame (3.2 GB of floats)."""
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_AS, (5 << 29, 5 << 29))\n"
            "from startrack.cli import main; sys.exit(main(sys.argv[1:]))")
    proc = subprocess.run([sys.executable, "-c", code, "simulate", "--width", "20000", "--height", "20000",
                           "--max-pixels", "400000000", "--no-noise", "--out", str(tmp_path / "big.fits")],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("startrack simulate: error: out of memory") and "Traceback" not in proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and list(tmp_path.iterdir()) == []


def test_sigterm_during_a_sequence_leaves_no_temporary_file(tmp_path):
    """Before: SIGTERM killed the process in the middle of a write and left ``.tmp`` files behind."""
    folder = tmp_path / "seq"
    proc = subprocess.Popen([*STARTRACK, "simulate", "--frames", "400", "--width", "256", "--height", "256",
                             "--format", "png", "--seed", "3", "--out", str(folder)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not (folder.is_dir() and len(list(folder.glob("frame_*.png"))) >= 2) and time.monotonic() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "startrack simulate: terminated" in err, err
    names = [p.name for p in folder.iterdir()]
    assert names and not [n for n in names if n.endswith(".tmp")]
    for png in folder.glob("*.png"):  # every frame there is whole, with its sidecar
        assert (folder / f"{png.stem}.truth.json").is_file()


def test_a_cache_folder_that_cannot_be_written_is_one_warning_line(tmp_path):
    """Before: the rebuilt table was thrown away and the command failed."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    env = {**os.environ, "STARTRACK_CACHE_DIR": str(blocker / "cache")}
    proc = subprocess.run([*STARTRACK, "availability", "--fov-deg", "10", "--pointings", "10"], env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    warning = [line for line in proc.stderr.splitlines() if "warning" in line]
    assert len(warning) == 1 and warning[0].startswith("startrack availability: warning: cannot write the cache")
    assert "P(< 3 stars)" in proc.stdout


@pytest.mark.parametrize("command", ["detect", "calibrate", "rate", "analyse"])
def test_max_pixels_refuses_a_larger_image_in_every_command_that_reads_images(tmp_path, command):
    """--max-pixels existed only on track and simulate before (the limit message named it anyway).
    analyse goes on past an image it cannot read and says why on stderr; with no image it could read
    (this one) it stops with exit 2 (it wrote empty figures and exited 0 before)."""
    path = tmp_path / "frame.png"
    write_png(path, np.zeros((64, 80), dtype=np.uint16))
    argv = {"detect": ["detect", path], "calibrate": ["calibrate", path],
            "rate": ["rate", path, "--exposure-s", "1", "--fov-deg", "10"],
            "analyse": ["analyse", "histograms", path, "--out", tmp_path / "a"]}[command]
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv] + ["--max-pixels", "1000"])
    assert code == 2, err.getvalue()
    assert "over the limit of 1,000 px" in err.getvalue(), err.getvalue()


def test_a_time_past_the_known_leap_seconds_is_one_warning_in_words(realdata_dir):
    """Before: ERFA's 'ERFA function "dtf2d" yielded 1 of "dubious year (Note 6)"'."""
    photo = realdata_dir / "smroid-cedar-solve" / "crappy.jpg"
    proc = subprocess.run([*STARTRACK, "solve", str(photo), "--fov-deg", "10.2", "--time", "2045-01-01T00:00:00"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    warning = [line for line in proc.stderr.splitlines() if "warning" in line]
    assert warning == ["startrack solve: warning: " + DUBIOUS_YEAR], proc.stderr
