"""The ``startrack`` command line: every subcommand through ``startrack.cli.main`` in-process,
plus one run of the installed console script.

Exit codes: 0 success, 1 an expected failure (printed as a result with its status and reason),
2 misuse (one line ``startrack <cmd>: error: ...`` on stderr, nothing on stdout, no traceback).
One simulated sky (seed 1, 1024 x 1024 px, 15 deg) is written once as FITS, PNG and TIFF and
shared by the tests of this module.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image as PILImage
from scipy.spatial.transform import Rotation

from cli_runner import run
from startrack.camera import Camera
from startrack.cli import SUBCOMMANDS
from startrack.cli._progress import ensure_database
from startrack.frames import angle_between, attitude_error, boresight, rotation_from_radec_roll
from startrack.io import read_image, write_fits, write_png
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import ARCSEC, DEG, PIXEL

SEED = 1
SIM_SIZE_PX = 1024
SIZE = ("--width", SIM_SIZE_PX, "--height", SIM_SIZE_PX)
SOLUTION_KEYS = {"status", "ra_deg", "dec_deg", "roll_deg", "fov_deg", "qx", "qy", "qz", "qw", "matches",
                 "false_match_prob", "solve_time_s"}
PLEIADES = Path(__file__).resolve().parents[3] / "shared" / "realdata" / "smroid-cedar-solve" / "pleiades.jpg"


def strict_json(text: str) -> dict:
    """Parse JSON, refusing the NaN / Infinity extensions."""
    return json.loads(text, parse_constant=lambda name: pytest.fail(f"non-standard JSON constant {name}"))


def assert_no_traceback(*texts: str) -> None:
    for text in texts:
        assert "Traceback" not in text


def assert_misuse(result: tuple[int, str, str], command: str, *words: str) -> str:
    """Exit 2, nothing on stdout, exactly one stderr line naming the command and the problem."""
    code, out, err = result
    assert_no_traceback(out, err)
    assert code == 2, err
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"startrack {command}: error: ")
    for word in words:
        assert word in lines[0]
    return lines[0]


def assert_unsolved(result: tuple[int, str, str], status: str, *words: str) -> None:
    """Exit 1 with the status and reason printed as a table; nothing on stderr."""
    code, out, err = result
    assert_no_traceback(out, err)
    assert code == 1, err
    assert err == ""
    table = parse_table(out)
    assert table["status"] == status
    for word in words:
        assert word in table["reason"]


def parse_table(out: str) -> dict[str, str]:
    """The human table: a 12-character name column, then the value."""
    return {line[:12].strip(): line[12:].strip() for line in out.splitlines() if line.strip()}


def rotation_from_quaternion(data: dict, prefix: str = "") -> Rotation:
    return Rotation.from_quat([data[prefix + k] for k in ("qx", "qy", "qz", "qw")])


def boresight_of_radec(ra_deg: float, dec_deg: float) -> np.ndarray:
    return boresight(rotation_from_radec_roll(ra_deg * DEG, dec_deg * DEG, 0.0))


@pytest.fixture(scope="module", autouse=True)
def _database_loaded():
    """Load the default pattern database (built on a fresh cache, ~15-40 s) before any test, so
    its progress bar on stderr never lands in a test's captured output."""
    with contextlib.redirect_stderr(io.StringIO()):
        ensure_database()


@pytest.fixture(scope="module")
def sim(tmp_path_factory) -> dict[str, Path]:
    """``simulate --seed 1`` written as sim.fits, sim16.png and simtif.tif (+ truth sidecars), and
    a CSV star list (x, y, mag) made from the PNG's truth sidecar."""
    folder = tmp_path_factory.mktemp("sim")
    paths = {"fits": folder / "sim.fits", "png": folder / "sim16.png", "tif": folder / "simtif.tif"}
    for path in paths.values():
        code, _, err = run("simulate", "--seed", SEED, "--out", path)
        assert code == 0, err
    truth = json.loads((folder / "sim16.truth.json").read_text())
    paths["csv"] = folder / "stars.csv"
    with open(paths["csv"], "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["x", "y", "mag"])
        writer.writerows((s["x"], s["y"], s["mag"]) for s in truth["stars"])
    paths["truth"] = folder / "sim16.truth.json"
    return paths


# ---------------------------------------------------------------- help, usage, version


ATTITUDE_COMMANDS = {"solve", "solve-stars", "solve-rig", "simulate", "demo"}
"""Commands whose output is an attitude (table or JSON with the quaternion columns)."""


@pytest.mark.parametrize("command", list(SUBCOMMANDS))
def test_help_of_every_subcommand_exits_0_and_documents_the_output(command):
    code, out, err = run(command, "--help")
    assert code == 0, err
    assert out.startswith(f"usage: startrack {command}")
    assert "exit status" in out.lower()
    if command in ATTITUDE_COMMANDS:
        assert "--json" in out
        assert "qx, qy, qz, qw" in out  # the JSON keys are documented in the epilog


def test_top_level_help_version_and_unknown_command():
    code, out, _ = run("--help")
    assert code == 0 and all(name in out for name in SUBCOMMANDS)
    code, out, _ = run("--version")
    assert code == 0 and out.startswith("startrack ")
    for argv in ([], ["frobnicate"]):
        code, out, err = run(*argv)
        assert code == 2 and out == ""
        assert err.splitlines()[-1].startswith("startrack: error: ")


def test_argparse_errors_exit_2_with_the_usage_and_one_error_line():
    for argv, words in ((["solve"], "required"), (["solve-stars", "x.csv", "--width", "0", "--height", "5"],
                                                   "--width"),
                        (["solve", "x.png", "--fov-deg", "10", "--camera", "sunsat"], "not allowed"),
                        (["solve", "x.jpg", "--utc-offset-hours=30"], "from -14 to 14, got 30"),
                        (["analyse", "x", "--utc-offset-hours", "nan"], "from -14 to 14, got nan"),
                        (["detect", "x.fits", "--max-stars", "0"], "expected a whole number >= 1, got 0")):
        code, out, err = run(*argv)
        assert_no_traceback(out, err)
        assert code == 2 and out == ""
        assert err.startswith("usage: ")
        last = err.splitlines()[-1]
        assert last.startswith(f"startrack {argv[0]}: error: ") and words in last


# ---------------------------------------------------------------- simulate -> solve round trips


def test_simulate_writes_the_truth_as_fits_cards_and_16_bit_png_tiff(sim):
    header = read_image(sim["fits"]).header
    assert {"TRUE_RA", "TRUE_DEC", "TRUEROLL", "TRUE_QX", "TRUE_QY", "TRUE_QZ", "TRUE_QW", "FOCALPX"} <= set(header)
    assert header["CATEPOCH"] == 2000.0  # the solvers' default epoch
    for kind in ("png", "tif"):
        image = read_image(sim[kind])
        assert image.bit_depth == 16 and image.data.dtype == np.uint16
        assert image.data.shape == (SIM_SIZE_PX, SIM_SIZE_PX)
        assert image.data.max() > 1000  # stars, not a blank frame
    truth = json.loads(sim["truth"].read_text())
    assert truth["ra_deg"] == pytest.approx(header["TRUE_RA"], abs=1e-9)
    assert len(truth["stars"]) > 50


def test_simulate_json_lists_the_files_and_the_truth(tmp_path):
    out = tmp_path / "small.tif"
    code, text, err = run("simulate", "--seed", 7, "--width", 128, "--height", 96, "--fov-deg", 20, "--out", out,
                          "--json", "--ra-deg", 83.8, "--dec-deg", -5.4, "--roll-deg", 30)
    assert code == 0, err
    truth = strict_json(text)
    assert truth["seed"] == 7 and truth["files"] == [str(out), str(tmp_path / "small.truth.json")]
    assert {"ra_deg", "dec_deg", "roll_deg", "qx", "qy", "qz", "qw", "epoch_jyear", "camera", "stars"} <= set(truth)
    assert (truth["ra_deg"], truth["dec_deg"], truth["roll_deg"]) == pytest.approx((83.8, -5.4, 30.0), abs=1e-9)
    assert truth["camera"]["width"] == 128 and truth["camera"]["height"] == 96
    assert read_image(out).data.shape == (96, 128)


def test_solve_fits_json_matches_the_truth_cards(sim):
    code, out, err = run("solve", sim["fits"], "--json")
    assert code == 0, err
    solution = strict_json(out)
    assert SOLUTION_KEYS <= set(solution)
    assert solution["status"] == "ok" and solution["reason"] == ""
    assert len(solution["matches"]) >= 20
    assert {"index", "hip", "residual_arcsec", "x", "y"} <= set(solution["matches"][0])
    assert solution["false_match_prob"] < 1e-6
    assert solution["fov_deg"] == pytest.approx(15.0, rel=0.01)
    # the epoch the help promises: the simulator's CATEPOCH card (J2000.0)
    assert (solution["epoch_jyear"], solution["epoch_source"]) == (2000.0, "CATEPOCH")

    header = read_image(sim["fits"]).header
    two_px = 2 * PIXEL / header["FOCALPX"]  # radians
    truth_rot = rotation_from_radec_roll(header["TRUE_RA"] * DEG, header["TRUE_DEC"] * DEG, header["TRUEROLL"] * DEG)
    solved_bore = boresight_of_radec(solution["ra_deg"], solution["dec_deg"])
    assert angle_between(solved_bore, boresight(truth_rot)) < two_px
    solved_rot = rotation_from_quaternion(solution)
    assert attitude_error(truth_rot, solved_rot) < two_px  # quaternion and roll too
    # the RA / Dec / roll printed describe the same attitude as the quaternion
    printed = rotation_from_radec_roll(*(solution[k] * DEG for k in ("ra_deg", "dec_deg", "roll_deg")))
    assert attitude_error(printed, solved_rot) < 1e-6


def test_the_table_and_the_json_name_the_constellation_astropy_names(sim):
    from astropy.coordinates import SkyCoord

    header = read_image(sim["fits"]).header
    expected = SkyCoord(header["TRUE_RA"], header["TRUE_DEC"], unit="deg").get_constellation()
    code, out, err = run("solve", sim["fits"], "--fov-deg", 15)
    assert code == 0 and parse_table(out)["RA, Dec"].endswith(f"(boresight, ICRS), in {expected}"), err
    code, out, err = run("solve", sim["fits"], "--fov-deg", 15, "--json")
    assert code == 0 and strict_json(out)["constellation"] == expected, err
    solution = strict_json(out)
    assert solution["pixel_scale_arcsec"] == pytest.approx(np.degrees(1 / solution["focal_px"]) * 3600, rel=1e-3)
    from startrack.analysis import solution_title  # the --plot picture's and the web tool's title
    from startrack.solve import solve_image

    assert f"({expected})" in solution_title(solve_image(sim["fits"], fov_deg=15.0))


@pytest.mark.parametrize("kind", ["png", "tif"])
def test_solve_png_and_tiff_table(sim, kind):
    code, out, err = run("solve", sim[kind], "--fov-deg", 15)
    assert code == 0, err
    table = parse_table(out)
    assert table["status"] == "solved"
    assert {"RA, Dec", "roll", "FOV", "stars", "residual", "false match", "epoch", "time", "qx qy qz qw"} <= set(table)
    assert table["epoch"] == "J2000.00 (default)"  # PNG and TIFF carry no CATEPOCH card
    truth = json.loads(sim["truth"].read_text())
    quaternion = dict(zip(("qx", "qy", "qz", "qw"), map(float, table["qx qy qz qw"].split()), strict=True))
    two_px = 2 * PIXEL / truth["camera"]["fx"]
    assert attitude_error(rotation_from_quaternion(truth), rotation_from_quaternion(quaternion)) < two_px


def test_solve_stars_csv_from_the_truth(sim):
    code, out, err = run("solve-stars", sim["csv"], "--width", SIM_SIZE_PX, "--height", SIM_SIZE_PX, "--json")
    assert code == 0, err
    solution = strict_json(out)
    assert SOLUTION_KEYS <= set(solution) and solution["status"] == "ok"
    truth = json.loads(sim["truth"].read_text())
    assert len(solution["matches"]) >= 0.9 * len(truth["stars"])
    # true positions, same epoch: the attitude is exact to a small fraction of a pixel
    tenth_px = 0.1 * PIXEL / truth["camera"]["fx"]
    assert attitude_error(rotation_from_quaternion(truth), rotation_from_quaternion(solution)) < tenth_px


def _other_programs_lists(truth: dict, folder: Path) -> dict[str, Path]:
    """The truth's stars as astrometry.net's xylist (a FITS table of X, Y, FLUX) and as
    SExtractor's ASCII_HEAD catalog, both with 1-based positions as those programs write them."""
    from astropy.io import fits

    x, y, mag = (np.array([s[k] for s in truth["stars"]]) for k in ("x", "y", "mag"))
    flux = 10 ** (-0.4 * mag)
    xylist = folder / "field.xyls"
    primary = fits.PrimaryHDU()
    primary.header["IMAGEW"], primary.header["IMAGEH"] = SIM_SIZE_PX, SIM_SIZE_PX  # as solve-field's .axy says
    fits.HDUList([primary, fits.BinTableHDU.from_columns(
        [fits.Column(name=k, format="D", array=v) for k, v in (("X", x + 1), ("Y", y + 1), ("FLUX", flux))])]
    ).writeto(xylist, overwrite=True)
    catalog = folder / "field.cat"
    catalog.write_text("#   1 NUMBER  Running object number\n#   2 X_IMAGE  Object position along x  [pixel]\n"
                       "#   3 Y_IMAGE  Object position along y  [pixel]\n#   4 MAG_AUTO  Kron-like magnitude  [mag]\n"
                       + "".join(f"{k + 1} {a + 1:.6f} {b + 1:.6f} {m:.4f}\n" for k, (a, b, m) in enumerate(zip(
                           x, y, mag, strict=True))))
    return {"xylist": xylist, "sextractor": catalog}


@pytest.mark.parametrize("kind", ["xylist", "sextractor"])
def test_solve_stars_reads_astrometry_net_and_sextractor_lists_in_our_pixels(sim, tmp_path, kind):
    """Their 1-based positions made 0-based: the attitude is the truth's to a tenth of a pixel,
    where a pixel's shift of every star would turn it by a whole pixel."""
    truth = json.loads(sim["truth"].read_text())
    code, out, err = run("solve-stars", _other_programs_lists(truth, tmp_path)[kind], *SIZE, "--json")
    assert code == 0, err
    tenth_px = 0.1 * PIXEL / truth["camera"]["fx"]
    assert attitude_error(rotation_from_quaternion(truth), rotation_from_quaternion(strict_json(out))) < tenth_px


def test_solve_stars_takes_the_image_size_from_an_axy_header_and_asks_for_it_otherwise(sim, tmp_path):
    truth = json.loads(sim["truth"].read_text())
    code, out, err = run("solve-stars", _other_programs_lists(truth, tmp_path)["xylist"], "--json")
    assert code == 0, err
    tenth_px = 0.1 * PIXEL / truth["camera"]["fx"]  # the optical axis at the centre of the size it read
    assert attitude_error(rotation_from_quaternion(truth), rotation_from_quaternion(strict_json(out))) < tenth_px
    code, out, err = run("solve-stars", sim["csv"])
    assert code == 2 and "--width and --height are required unless --camera or the star list's FITS header" in err


def test_solve_stars_match_index_is_the_row_of_the_star_list(sim, tmp_path):
    truth = json.loads(sim["truth"].read_text())
    stars = [truth["stars"][i] for i in np.random.default_rng(5).permutation(len(truth["stars"]))]
    starlist = tmp_path / "shuffled.csv"  # rows not brightest first; the hip column is ignored by the reader
    starlist.write_text("x,y,mag,hip\n" + "".join(f"{s['x']},{s['y']},{s['mag']},{s['hip']}\n" for s in stars))
    code, out, err = run("solve-stars", starlist, *SIZE, "--json")
    assert code == 0, err
    matches = strict_json(out)["matches"]
    assert [stars[m["index"]]["hip"] for m in matches] == [m["hip"] for m in matches]


@pytest.mark.parametrize("method", ["pyramid", "nvertex-4"])
def test_solve_stars_with_another_matcher(sim, method):
    truth = json.loads(sim["truth"].read_text())
    fov = str(truth["camera"]["fov_deg"])
    code, out, err = run("solve-stars", sim["csv"], *SIZE, "--fov-deg", fov, "--method", method, "--json")
    assert code == 0, err
    solution = strict_json(out)
    tenth_px = 0.1 * PIXEL / truth["camera"]["fx"]
    assert attitude_error(rotation_from_quaternion(truth), rotation_from_quaternion(solution)) < tenth_px


def test_solve_stars_unknown_matcher_is_refused(sim):
    code, out, err = run("solve-stars", sim["csv"], *SIZE, "--method", "telepathy")
    assert code == 2 and out == "" and "--method" in err and "quads" in err and "Traceback" not in err


def test_a_pair_matcher_without_a_known_fov_is_refused(sim):
    assert_misuse(run("solve-stars", sim["csv"], *SIZE, "--method", "pyramid"), "solve-stars", "within 5 %")


def test_solve_stars_duplicate_rows_are_refused_cleanly(sim, tmp_path):
    rows = sim["csv"].read_text().splitlines()
    starlist = tmp_path / "duplicates.csv"
    starlist.write_text("\n".join([*rows[:8], rows[1], rows[2]]) + "\n")
    assert_misuse(run("solve-stars", starlist, *SIZE), "solve-stars", "same position")


def test_solve_stars_with_a_camera_preset(tmp_path):
    png = tmp_path / "sunsat.png"
    code, _, err = run("simulate", "--camera", "sunsat", "--seed", 4, "--no-noise", "--out", png)
    assert code == 0, err
    truth = json.loads((tmp_path / "sunsat.truth.json").read_text())
    starlist = tmp_path / "sunsat.csv"
    starlist.write_text("x,y,mag\n" + "".join(f"{s['x']},{s['y']},{s['mag']}\n" for s in truth["stars"]))
    code, out, err = run("solve-stars", starlist, "--camera", "sunsat", "--json")
    assert code == 0, err
    solution = strict_json(out)
    assert solution["fov_deg"] == pytest.approx(truth["camera"]["fov_deg"], rel=1e-9)  # fixed by the preset
    tenth_px = 0.1 * PIXEL / truth["camera"]["fx"]
    assert attitude_error(rotation_from_quaternion(truth), rotation_from_quaternion(solution)) < tenth_px
    # a size that disagrees with the preset is refused
    assert_misuse(run("solve-stars", starlist, "--camera", "sunsat", "--width", 100), "solve-stars",
                  "--width", "sunsat")


def test_demo_writes_its_files_and_solves(tmp_path):
    out_dir = tmp_path / "demo-out"
    code, out, err = run("demo", "--seed", 2, "--out", out_dir)
    assert code == 0, err
    assert_no_traceback(out, err)
    for name in ("demo.png", "demo.truth.json", "demo_solved.png"):
        assert (out_dir / name).stat().st_size > 0
    lines = parse_table(out)
    assert lines["status"] == "solved"
    total_arcsec = float(lines["error"].split()[0])
    pixel_scale_arcsec = float(lines["FOV"].split()[0]) * 3600 / SIM_SIZE_PX
    assert total_arcsec < 2 * pixel_scale_arcsec
    printed_scale = float(lines["FOV"].split(" arcsec/px")[0].split()[-1])  # the FOV row's scale at the centre
    assert printed_scale == pytest.approx(pixel_scale_arcsec, rel=0.01)  # a 15 deg field: 1 % from FOV / width


@pytest.mark.skipif(not PLEIADES.is_file(), reason=f"real image {PLEIADES} is absent (../shared/realdata)")
def test_solve_real_pleiades_photo():
    code, out, err = run("solve", PLEIADES, "--fov-range-deg", 5, 35)
    assert code == 0, err
    lines = parse_table(out)
    assert lines["status"] == "solved"
    ra_text, dec_text = lines["RA, Dec"].split(",")[:2]
    ra_deg, dec_deg = float(ra_text.split()[0]), float(dec_text.split()[0])
    # astrometry.net: RA 56.182243, Dec 25.464971, 71.65 arcsec / px (realdata/truth.csv)
    two_px = 2 * 71.65 / 3600 * DEG
    assert angle_between(boresight_of_radec(ra_deg, dec_deg), boresight_of_radec(56.182243, 25.464971)) < two_px


# ---------------------------------------------------------------- bad images


def _bad_images(folder: Path, good_png: Path) -> dict[str, Path]:
    files = {name: folder / name for name in ("empty.png", "truncated.png", "text.png", "zero.png",
                                              "saturated.png", "nan.fits", "one.png")}
    files["empty.png"].write_bytes(b"")
    files["truncated.png"].write_bytes(good_png.read_bytes()[:3000])
    files["text.png"].write_text("this is not an image\n")
    write_png(files["zero.png"], np.zeros((64, 64), np.uint8))
    write_png(files["saturated.png"], np.full((64, 64), 255, np.uint8))
    write_fits(files["nan.fits"], np.full((64, 64), np.nan, np.float32))
    write_png(files["one.png"], np.zeros((1, 1), np.uint8))
    return files


@pytest.fixture(scope="module")
def bad_images(tmp_path_factory, sim) -> dict[str, Path]:
    return _bad_images(tmp_path_factory.mktemp("bad"), sim["png"])


@pytest.mark.parametrize(("name", "words"), [
    ("missing.png", ("missing.png", "does not exist")),
    ("empty.png", ("empty.png", "empty")),
    ("truncated.png", ("truncated.png", "truncated")),
    ("text.png", ("text.png", "not an image")),
    ("nan.fits", ("nan.fits", "no finite pixel")),
    ("one.png", ("one.png", "2 x 2")),
])
def test_solve_bad_image_is_misuse(bad_images, name, words):
    path = bad_images.get(name, bad_images["empty.png"].with_name(name))
    assert_misuse(run("solve", path), "solve", *words)
    assert_misuse(run("solve", path, "--json"), "solve", *words)  # no partial JSON either


@pytest.mark.parametrize(("name", "words"), [("zero.png", ("blank", "0")), ("saturated.png", ("saturated", "255"))])
def test_solve_uniform_image_is_an_expected_failure(bad_images, name, words):
    assert_unsolved(run("solve", bad_images[name]), "too_few_stars", *words)
    code, out, err = run("solve", bad_images[name], "--json")
    assert code == 1 and err == ""
    result = strict_json(out)
    assert result["status"] == "too_few_stars" and result["n_detections"] == 0
    assert "ra_deg" not in result


# ---------------------------------------------------------------- bad star lists and FOVs


@pytest.fixture(scope="module")
def bad_lists(tmp_path_factory, sim) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("lists")
    rows = sim["csv"].read_text().splitlines()
    files = {"two.csv": rows[:3], "nan.csv": [*rows[:6], "nan,12.5,5.0"], "outside.csv": [*rows[:6], "1500,12.5,5.0"]}
    paths = {}
    for name, lines in files.items():
        paths[name] = folder / name
        paths[name].write_text("\n".join(lines) + "\n")
    paths["binary.csv"] = folder / "binary.csv"
    paths["binary.csv"].write_bytes(sim["png"].read_bytes()[:200])
    return paths


def test_solve_stars_two_stars_is_an_expected_failure(bad_lists):
    assert_unsolved(run("solve-stars", bad_lists["two.csv"], *SIZE), "too_few_stars", "got 2")


@pytest.mark.parametrize(("name", "words"), [
    ("nan.csv", ("nan.csv", "line 7", "finite")),
    ("outside.csv", ("outside.csv", "(1500, 12.5)", "outside the 1024 x 1024 image")),
    ("binary.csv", ()),
    ("binary.csv", ("binary.csv", "not a text CSV file in UTF-8 or UTF-16")),
    ("missing.csv", ("missing.csv", "does not exist")),
])
def test_solve_stars_bad_list_is_misuse(bad_lists, name, words):
    path = bad_lists.get(name, bad_lists["two.csv"].with_name(name))
    assert_misuse(run("solve-stars", path, *SIZE), "solve-stars", *words)


@pytest.mark.parametrize(("fov", "words"), [
    (("--fov-deg", -5), ("--fov-deg", "-5", "0.5 and 150")),
    (("--fov-deg", 500), ("--fov-deg", "500")),
    (("--fov-deg", "nan"), ("--fov-deg", "nan")),
    (("--fov-range-deg", 30, 10), ("--fov-range-deg", "LO <= HI", "30 10")),
    (("--fov-range-deg", 0, 10), ("--fov-range-deg", "got 0")),
    (("--camera", "no-such-camera"), ("no-such-camera", "sunsat")),
    (("--epoch", 5), ("--epoch", "Julian year")),
])
def test_bad_fov_or_epoch_is_misuse_for_both_solvers(sim, fov, words):
    assert_misuse(run("solve", sim["fits"], *fov), "solve", *words)
    assert_misuse(run("solve-stars", sim["csv"], *SIZE, *fov), "solve-stars", *words)


def test_options_are_checked_before_the_file(tmp_path):
    line = assert_misuse(run("solve", tmp_path / "missing.png", "--fov-deg", -5), "solve")
    assert "--fov-deg" in line


# ---------------------------------------------------------------- simulate output paths


@pytest.mark.parametrize(("out", "words"), [
    ("no-such-folder/x.fits", ("no-such-folder", "does not exist")),
    ("no-such-folder/x.png", ("no-such-folder", "does not exist")),
    ("x.jpg", ("x.jpg", ".fits, .png or .tif")),
    ("x", (".fits, .png or .tif",)),
])
def test_simulate_bad_out_fails_cleanly_and_writes_nothing(tmp_path, out, words):
    assert_misuse(run("simulate", "--seed", SEED, "--out", tmp_path / out), "simulate", *words)
    assert list(tmp_path.iterdir()) == []


def test_simulate_out_is_a_folder(tmp_path):
    (tmp_path / "d.fits").mkdir()
    assert_misuse(run("simulate", "--seed", SEED, "--out", tmp_path / "d.fits"), "simulate", "folder")
    assert list((tmp_path / "d.fits").iterdir()) == []


@pytest.mark.parametrize(("options", "words"), [
    (("--seed", -1), ("--seed",)),
    (("--camera", "sunsat", "--width", 100), ("--camera", "--width")),
    (("--ra-deg", 10), ("--dec-deg",)),
    (("--ra-deg", 10, "--dec-deg", 95), ("--dec-deg", "95")),
    (("--exposure-s", 0), ("--exposure-s",)),
    (("--epoch", 1), ("--epoch",)),
    (("--fov-deg", -5), ("--fov-deg -5", "between 0 and 180")),
    (("--fov-deg", 500), ("--fov-deg 500", "between 0 and 180")),
    (("--width", 1), ("--width 1", "at least 2 px")),
])
def test_simulate_bad_scene_options_fail_cleanly(tmp_path, options, words):
    assert_misuse(run("simulate", *options, "--out", tmp_path / "x.fits"), "simulate", *words)
    assert list(tmp_path.iterdir()) == []


def test_demo_out_is_a_file(tmp_path):
    target = tmp_path / "file.txt"
    target.write_text("keep me")
    assert_misuse(run("demo", "--seed", 2, "--out", target), "demo", "is a file")
    assert target.read_text() == "keep me"


# ---------------------------------------------------------------- the installed console script


def test_console_script_missing_file_prints_one_line_and_no_traceback(tmp_path):
    script = Path(sys.executable).with_name("startrack")
    command = [str(script)] if script.is_file() else [sys.executable, "-m", "startrack"]
    missing = tmp_path / "missing.fits"
    done = subprocess.run([*command, "solve", str(missing)], capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr.splitlines() == [f"startrack solve: error: {missing}: file does not exist"]


def test_counts_take_whole_numbers_in_any_notation():
    """--max-pixels 1e9 was refused while STARTRACK_MAX_PIXELS=1e9 was taken; and --max-stars 0
    was told to give a whole number 'of pixels'."""
    from startrack.cli._common import positive_count

    assert positive_count("1e9") == positive_count("1_000_000_000") == 10**9
    for text in ("1.5", "inf", "nan", "abc", "0", "-3"):
        with pytest.raises(argparse.ArgumentTypeError):
            positive_count(text)


def test_solve_searches_the_field_an_ultra_wide_photos_exif_states_first(tmp_path):
    """A 110 deg JPEG whose EXIF gives a 35 mm focal length of 13 mm (108 deg): solved with no
    option, the command saying on stderr which field it searched first."""
    camera = Camera.from_fov(1500, 1000, 110.0).with_distortion(k1=-0.005)
    truth = rotation_from_radec_roll(250 * DEG, -60 * DEG, 30 * DEG)
    sim = simulate_frame(camera, truth, max_mag=6.0, sensor=get_sensor_preset("generic-cmos"), rng=3)
    counts = sim.image.astype(np.float64)
    pixels = np.clip((counts - np.median(counts)) * 2 + 20, 0, 255).astype(np.uint8)
    exif = PILImage.Exif()
    exif.get_ifd(0x8769)[0xA405] = 13  # FocalLengthIn35mmFilm, in the Exif IFD
    path = tmp_path / "ultra_wide.jpg"
    PILImage.fromarray(pixels).save(path, quality=95, exif=exif)
    code, out, err = run("solve", path, "--json")
    assert code == 0, err
    assert "states a field of view of 108.3 deg: searching 70.0-119.2 deg first" in err
    solution = json.loads(out)
    assert solution["fov_deg"] == pytest.approx(110.0, rel=0.01) and solution["fov_source"] == "header"
    solved = rotation_from_radec_roll(solution["ra_deg"] * DEG, solution["dec_deg"] * DEG, solution["roll_deg"] * DEG)
    assert attitude_error(solved, truth) < camera.pixel_scale_arcsec * ARCSEC  # within a pixel's angle


def test_solve_and_detect_read_a_bayer_mosaic_fits_at_full_resolution(sim, tmp_path):
    """The simulated frame through an RGGB filter mosaic (R, G, B passing 0.45, 1.0 and 0.6 of the
    light above the bias), saved with BAYERPAT: both commands say they read a mosaic, the solve keeps
    the file's pixels (the truth within 2 px) and the stars are found where the grey frame has them."""
    grey = read_image(sim["fits"])
    h, w = grey.data.shape
    response = np.tile(np.array([[0.45, 1.0], [1.0, 0.6]]), (h // 2, w // 2))
    bias = float(np.percentile(grey.data, 1))
    mosaic = np.clip((grey.data - bias) * response + bias, 0, 65535).astype(np.uint16)
    path = write_fits(tmp_path / "osc.fits", mosaic, {**{k: grey.header[k] for k in ("CATEPOCH", "TRUE_RA", "TRUE_DEC",
                                                                                     "TRUEROLL", "FOCALPX")},
                                                      "BAYERPAT": "RGGB"})
    code, out, err = run("solve", path, "--json")
    assert code == 0, err
    assert "a colour-filter (Bayer) mosaic (pattern RGGB): read at full resolution" in err
    solution = strict_json(out)
    header = grey.header
    truth_rot = rotation_from_radec_roll(header["TRUE_RA"] * DEG, header["TRUE_DEC"] * DEG, header["TRUEROLL"] * DEG)
    assert attitude_error(truth_rot, rotation_from_quaternion(solution)) < 2 * PIXEL / header["FOCALPX"]
    code, out, err = run("detect", path, "--json")
    assert code == 0 and "pattern RGGB" in err
    stars = strict_json(out)["stars"]
    code, grey_out, _ = run("detect", sim["fits"], "--json")
    grey_stars = strict_json(grey_out)["stars"][:10]
    for star in grey_stars:  # the ten brightest of the grey frame, each found within 0.3 px (full-resolution px)
        assert min(np.hypot(s["x"] - star["x"], s["y"] - star["y"]) for s in stars) < 0.3


def test_solve_plot_draws_the_image_solved_or_not(sim, tmp_path):
    """--plot writes a PNG of the image's size ratio whether or not the image solves, never over the
    image read, and is refused for a batch."""
    out = tmp_path / "solved.png"
    code, _, err = run("solve", sim["fits"], "--plot", out)
    assert code == 0, err
    with PILImage.open(out) as png:
        assert png.format == "PNG" and png.size[0] == png.size[1]  # the simulated frame is square
    blank = tmp_path / "blank.png"
    write_png(blank, np.full((120, 160), 200, dtype=np.uint16))
    code, _, err = run("solve", blank, "--plot", tmp_path / "blank-plot.png")
    assert code == 1 and (tmp_path / "blank-plot.png").stat().st_size > 0
    before = blank.read_bytes()
    code, _, err = run("solve", blank, "--plot", blank)
    assert code == 2 and "it is one of the inputs of this command" in err
    assert blank.read_bytes() == before
    code, _, err = run("solve", sim["png"], sim["tif"], "--plot", tmp_path / "two.png")
    assert code == 2 and "--plot draws the picture of one image" in err
    assert not (tmp_path / "two.png").exists()
