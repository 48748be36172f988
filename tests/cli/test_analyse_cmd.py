"""``startrack analyse``: list, one analysis over one and over two folders of simulated frames (the
files it writes against the library's result), a real image, and every misuse (exit 2, one line)."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from cli_runner import run as run_cli
from startrack import Camera
from startrack.analysis.postprocess import ANALYSES, records_from_images, run_analysis
from startrack.frames import random_rotations
from startrack.io._truth_files import write_frame
from startrack.simulate import get_sensor_preset, simulate_frame

CAMERA = Camera.from_fov(384, 320, 12.0)


def run(*argv) -> tuple[int, str, str]:
    """``startrack analyse ARGV`` in-process: (exit code, stdout, stderr)."""
    return run_cli("analyse", *argv)


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    """Two folders of two simulated FITS frames each; the second folder's frames share the first's
    names (so that compare pairs them) but are other skies."""
    sensor = get_sensor_preset("generic-cmos")
    out = []
    for f, seed in enumerate((1, 2)):
        folder = tmp_path_factory.mktemp(f"set{f}")
        for i, truth in enumerate(random_rotations(2, rng=seed)):
            sim = simulate_frame(CAMERA, truth, max_mag=7.0, sensor=sensor, rng=10 * f + i)
            write_frame(folder / f"frame{i}.fits", sim.image, sim.truth)
        out.append(folder)
    return out


def _csv(path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_list_names_every_analysis_and_its_parameters():
    code, out, err = run("list")
    assert code == 0 and not err
    for name, info in ANALYSES.items():
        assert f"\n{name} " in f"\n{out}"
        for key in info.params:
            assert f"{key}=" in out


def test_radial_over_a_folder_writes_what_the_library_computes(folders, tmp_path):
    code, out, err = run("radial", folders[0], "--fov-deg", 12, "--out", tmp_path / "radial")
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "radial").iterdir()) == ["radial.png", "radial_fit.csv",
                                                                       "radial_stars.csv"]
    expected = run_analysis("radial", [records_from_images(folders[0], solve_options={"fov_deg": 12.0})])
    stars = _csv(tmp_path / "radial" / "radial_stars.csv")
    assert [int(r["hip"]) for r in stars] == list(expected.tables["stars"]["hip"])
    np.testing.assert_allclose([float(r["residual_arcsec"]) for r in stars],
                               expected.tables["stars"]["residual_arcsec"])
    assert "2 of 2 solved" in out and "rms residual, arcsec" in out and "wrote " in out


def test_thresholds_take_a_list_parameter_and_compare_takes_two_folders(folders, tmp_path):
    code, out, err = run("thresholds", folders[0], "--fov-deg", 12, "--param", "sigmas=4,9", "--out", tmp_path)
    assert code == 0, err
    assert [r["value"] for r in _csv(tmp_path / "thresholds_thresholds.csv")] == ["4.0", "9.0"]
    code, out, err = run("compare", *folders, "--fov-range-deg", 10, 14, "--out", tmp_path)
    assert code == 0, err
    rows = _csv(tmp_path / "compare_images.csv")
    assert [r["record"] for r in rows] == ["frame0.fits", "frame1.fits"]
    assert all(r["solved_a"] == r["solved_b"] == "true" for r in rows)
    assert all(float(r["pointing_diff_arcsec"]) > 3600 for r in rows)  # other skies: degrees apart


def test_the_default_output_folder_is_named_for_the_analysis(folders, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run("histograms", folders[0], "--fov-deg", 12, "--param", "image=false")
    assert code == 0, err
    assert sorted(p.name for p in (tmp_path / "startrack-analysis" / "histograms").iterdir()) == [
        "histograms.png", "histograms_counts.csv", "histograms_spot_histograms.csv", "histograms_spots.csv"]


def test_a_real_photo(realdata_dir, tmp_path):
    code, out, err = run("magnitude", realdata_dir / "smroid-cedar-solve" / "roof.jpg", "--fov-deg", 10.2,
                         "--out", tmp_path)
    assert code == 0, err
    assert "roof.jpg: zero point, mag" in out and len(_csv(tmp_path / "magnitude_stars.csv")) >= 10


@pytest.mark.parametrize(("argv", "words"), [
    (("nope", "x"), "unknown analysis 'nope'; valid analyses: histograms"),
    (("radial", "{missing}"), "no such file or folder"),
    (("radial",), "radial takes 1 to 6 PATH(s), got 0"),
    (("compare", "{folder}"), "compare takes 2 PATH(s), got 1"),
    (("radial", "{folder}", "--param", "bins=3"), "unknown parameter 'bins'; valid parameters: none"),
    (("histograms", "{folder}", "--param", "bins"), "--param must be KEY=VALUE"),
    (("histograms", "{folder}", "--param", "bins=many"), "'bins' must be a whole number"),
    (("sweep", "{folder}", "--param", "setting=nope"), "'setting' must be one of"),
    (("radial", "{folder}", "--fov-deg", "500"), "--fov-deg"),
    (("radial", "{folder}", "--camera", "nope"), "valid presets"),
])
def test_misuse_exits_2_with_one_line(folders, tmp_path, argv, words):
    argv = [a.format(folder=folders[0], missing=tmp_path / "missing") for a in argv]
    code, out, err = run(*argv, "--out", tmp_path)
    assert code == 2 and not out
    assert err.count("\n") == 1 and err.startswith("startrack analyse: error: ")
    assert words in err
    assert not list(tmp_path.glob("*.png"))
