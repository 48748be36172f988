"""startrack solve-rig, simulate --rig and availability --rig, in-process."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from cli_runner import run

from .rigs import split_rig, two_heads


def assert_misuse(result, command: str, *words: str) -> None:
    code, out, err = result
    assert code == 2 and out == "" and len(err.splitlines()) == 1, err
    assert err.startswith(f"startrack {command}: error: ") and all(w in err for w in words), err


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    folder = tmp_path_factory.mktemp("rig")
    two_heads().save(folder / "rig.json")
    code, out, err = run("simulate", "--rig", folder / "rig.json", "--seed", 3, "--out", folder / "sim", "--json",
                         "--max-mag", 7.0)
    assert code == 0, err
    return folder, json.loads(out)


def test_help_documents_the_json_keys_and_the_exit_status():
    code, out, _ = run("solve-rig", "--help")
    assert code == 0 and "exit status" in out and "qx, qy, qz, qw" in out and "consistency_deg" in out


def test_simulate_rig_then_solve_rig_from_images_and_star_lists(simulated):
    folder, truth = simulated
    sim = folder / "sim"
    assert {p.name for p in sim.iterdir()} >= {"a.fits", "b.fits", "a.stars.csv", "b.stars.csv", "rig_truth.json"}
    expected = Rotation.from_quat([truth[k] for k in ("qx", "qy", "qz", "qw")])
    for inputs in ((f"a={sim / 'a.fits'}", f"b={sim / 'b.fits'}"), (f"a={sim / 'a.stars.csv'}", f"b={sim / 'b.fits'}")):
        code, out, err = run("solve-rig", folder / "rig.json", *inputs, "--json")
        assert code == 0, err
        data = json.loads(out)
        got = Rotation.from_quat([data[k] for k in ("qx", "qy", "qz", "qw")])
        assert np.degrees((expected * got.inv()).magnitude()) * 3600 < 10
        assert data["heads_used"] == ["a", "b"] and data["heads"]["b"]["n_matched"] > 10
        assert data["consistency_deg"] < 0.02
    code, out, _ = run("solve-rig", folder / "rig.json", f"a={sim / 'a.fits'}")
    assert code == 0 and out.startswith("status        solved")


def test_unsolved_exits_1(tmp_path, simulated):
    folder, _ = simulated
    path = tmp_path / "two.csv"
    with open(path, "w", newline="") as fh:
        csv.writer(fh).writerows([["x", "y"], [10, 20], [300, 400]])
    code, out, err = run("solve-rig", folder / "rig.json", f"a={path}", "--json")
    assert code == 1 and err == "" and json.loads(out)["status"] == "too_few_stars"


def test_misuse_exits_2_with_one_line(tmp_path, simulated):
    folder, _ = simulated
    sim = folder / "sim"
    assert_misuse(run("solve-rig", folder / "rig.json", f"c={sim / 'a.fits'}"), "solve-rig", "'c' is not a head")
    assert_misuse(run("solve-rig", folder / "rig.json", "a"), "solve-rig", "HEAD=FILE")
    assert_misuse(run("solve-rig", tmp_path / "none.json", f"a={sim / 'a.fits'}"), "solve-rig", "cannot read rig file")
    split_rig().save(tmp_path / "split.json")
    assert_misuse(run("solve-rig", tmp_path / "split.json", f"left={sim / 'a.fits'}"), "solve-rig", "split=IMAGE")
    assert_misuse(run("simulate", "--rig", folder / "rig.json", "--fov-deg", 10, "--out", tmp_path / "x"),
                  "simulate", "--fov-deg")
    assert_misuse(run("availability", "--rig", folder / "rig.json", "--time", "noon"), "availability", "ISO 8601")


def test_availability_of_a_rig(simulated):
    folder, _ = simulated
    code, out, err = run("availability", "--rig", folder / "rig.json", "--pointings", 2000, "--max-mag", 5.0,
                         "--json")
    assert code == 0, err
    data = json.loads(out)
    assert 0 < data["any_head"] <= data["joint"] <= 1 and set(data["heads"]) == {"a", "b"}
    assert data["heads"]["a"]["blinded"] > 0.3  # the Earth from 500 km
