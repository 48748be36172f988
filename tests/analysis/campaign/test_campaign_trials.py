"""Trials: their own random streams, how a solution is judged, and failure rows."""

from __future__ import annotations

import math

import campaign_faulty_level  # noqa: F401  (registers the level "test-faulty")
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.analysis.campaign._outcome import error_columns
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign._trials import Chunk, plan_chunks, run_chunk, run_trial, trial_rng, trial_schema
from startrack.units import ARCSEC

STARS = """
[campaign]
name = "t"
level = "stars"
trials = 6
seed = 99
[base]
max_mag = 6.0
[sweep]
fov_deg = [12.0, 20.0]
"""


def test_each_trial_has_its_own_stream():
    a = trial_rng(5, 1, 2).random(4)
    assert np.array_equal(a, trial_rng(5, 1, 2).random(4))
    assert not np.array_equal(a, trial_rng(5, 2, 1).random(4))
    assert not np.array_equal(a, trial_rng(6, 1, 2).random(4))


def test_a_trial_is_the_same_whatever_ran_before_it():
    spec = parse_spec(STARS)
    cell = spec.cells()[1]
    alone = run_trial(spec, cell, 4).row
    run_trial(spec, cell, 3)
    again = run_trial(spec, cell, 4).row
    for key in alone:
        if key not in ("time_s", "wall_s"):
            assert alone[key] == again[key] or (alone[key] != alone[key] and again[key] != again[key]), key
    assert alone["status"] == "OK" and alone["correct"]


def test_chunks_cover_every_trial_once():
    spec = parse_spec(STARS)
    chunks = plan_chunks(spec.cells(), 6, 4)
    assert [(c.cell.index, c.start, c.stop) for c in chunks] == [(0, 0, 4), (0, 4, 6), (1, 0, 4), (1, 4, 6)]


def test_a_chunk_table_follows_the_schema():
    spec = parse_spec(STARS)
    table = run_chunk(spec, Chunk(spec.cells()[0], 0, 2))
    assert table.schema == trial_schema(spec)
    assert table["trial"].to_pylist() == [0, 1] and table["fov_deg"].to_pylist() == [12.0, 12.0]


def test_a_raising_trial_becomes_an_error_row_with_its_traceback():
    text = STARS.replace('level = "stars"', 'level = "test-faulty"') + "\n"
    spec = parse_spec(text.replace("[sweep]", "[sweep]\nfail_fraction = [0.5]"))
    rows = run_chunk(spec, Chunk(spec.cells()[0], 0, 6)).to_pylist()
    failed = [r for r in rows if r["status"] == "ERROR"]
    ok = [r for r in rows if r["status"] != "ERROR"]
    assert failed and ok                      # with 0.5 both happen in 6 trials of this seed
    assert all("fails on purpose" in r["error"] and not r["solved"] for r in failed)
    assert all(math.isfinite(r["ra_deg"]) for r in failed)     # the true attitude is kept
    assert all(r["error"] == "" for r in ok)


def test_an_interruption_inside_compiled_code_stops_the_run_not_a_trial():
    """A SIGTERM or Ctrl-C that lands inside a compiled function comes back as a SystemError
    (an Exception) whose cause is the interruption; it was saved as an ERROR trial (which --resume
    then never reran) and the run went on."""
    text = STARS.replace('level = "stars"', 'level = "test-faulty"') + "\n"
    spec = parse_spec(text.replace("[sweep]", '[sweep]\nfail_fraction = [1.0]\nfault = ["interrupt"]'))
    with pytest.raises(KeyboardInterrupt):
        run_chunk(spec, Chunk(spec.cells()[0], 0, 2))


CAMERA = Camera.from_fov(1000, 800, 10.0)


def test_error_components_are_those_of_the_rotation_between_truth_and_estimate():
    truth = Rotation.from_euler("zyx", [30, 10, 5], degrees=True)
    offset = Rotation.from_rotvec(np.array([3.0, -4.0, 20.0]) * ARCSEC)   # camera frame
    estimate = offset.inv() * truth                                        # truth * estimate.inv() = offset
    cols = error_columns(truth, estimate, CAMERA, 5.0)
    assert cols["err_x_arcsec"] == pytest.approx(3.0, abs=1e-6)
    assert cols["err_y_arcsec"] == pytest.approx(-4.0, abs=1e-6)
    assert cols["err_roll_arcsec"] == pytest.approx(20.0, abs=1e-6)
    assert cols["err_cross_arcsec"] == pytest.approx(5.0, abs=1e-6)
    assert cols["err_total_arcsec"] == pytest.approx(math.sqrt(425.0), abs=1e-6)
    assert cols["correct"]


def test_correct_means_within_the_tolerance_at_the_image_corner():
    pixel = 1.0 / CAMERA.fx                                     # rad per pixel at the centre
    truth = Rotation.identity()
    weight = math.hypot(500 / CAMERA.fx, 400 / CAMERA.fy)     # roll -> motion at the corner
    just_in = Rotation.from_rotvec([0, 0, 4.9 * pixel / weight]).inv()
    just_out = Rotation.from_rotvec([0, 0, 5.1 * pixel / weight]).inv()
    assert error_columns(truth, just_in, CAMERA, 5.0)["correct"]
    assert not error_columns(truth, just_out, CAMERA, 5.0)["correct"]
    assert not error_columns(truth, None, CAMERA, 5.0)["correct"]
