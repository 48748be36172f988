"""A real error budget (small frames, synchronous): every "off" removes its source, the timing and
aberration cells give the errors their physics predicts, and the report and text show the budget."""

from __future__ import annotations

import math

import numpy as np
import pyarrow.compute as pc
import pytest

from startrack.analysis.campaign._budget_report import budget_text
from startrack.analysis.campaign._rerun import rerun_trial
from startrack.analysis.campaign._run import run_campaign
from startrack.calibrate._apparent import aberrate
from startrack.frames import angle_between, radec_to_vector
from startrack.units import ARCSEC

PLATE_ARCSEC = 8.0 * 3600.0 / 256  # about one pixel angle of the 8 deg, 256 px camera
RATE_DEG_S, TIMING_S, SPEED_KM_S = 0.2, 0.05, 100.0
SPEC = f"""
[campaign]
name = "budget-run"
level = "image"
mode = "budget"
trials = 8
seed = 21
[base]
width = 256
height = 256
fov_deg = 8.0
psf_sigma_px = 1.4
rate_deg_s = [{RATE_DEG_S}, 0.0, 0.0]
[budget]
sources = ["shot_noise", "quantisation", "distortion", "proper_motion", "aberration", "timing"]
repeats = 2
dithers = 2
timing_error_s = {TIMING_S}
aberration_annual = false
aberration_velocity_km_s = [0.0, 0.0, {SPEED_KM_S}]
k1 = 0.5
"""
NOISE_FREE = ("baseline", "quantisation", "distortion", "proper_motion", "aberration", "timing")


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("budget") / "out"
    table = run_campaign(SPEC, out, sync=True, report=True)
    return out, table


def _cell(table, source: str):
    rows = table.filter(pc.equal(table["source"], source)).sort_by("trial")
    return {name: rows[name].to_numpy(zero_copy_only=False) for name in rows.column_names}


def _err(cell) -> np.ndarray:
    return np.column_stack([cell["err_x_arcsec"], cell["err_y_arcsec"], cell["err_roll_arcsec"]])


def test_every_trial_solves_correctly(campaign):
    _, table = campaign
    assert table.num_rows == 8 * 8 and all(table["correct"].to_pylist())


def test_with_every_source_off_the_error_is_at_the_numerical_floor(campaign):
    _, table = campaign
    base = _cell(table, "baseline")
    assert np.sqrt(np.mean(base["err_cross_arcsec"] ** 2)) < 0.02 * PLATE_ARCSEC  # 0.02 px
    assert np.nanmin(base["centroid_rms_px"]) < 0.005  # one of the two fields has a blended pair: 0.07 px


def test_noise_free_cells_repeat_exactly_and_shot_noise_does_not(campaign):
    _, table = campaign
    for source in NOISE_FREE:
        err = _err(_cell(table, source))
        np.testing.assert_array_equal(err[0::2], err[1::2], err_msg=source)  # repeats: the same frame again
    shot = _err(_cell(table, "shot_noise"))
    assert np.all(np.abs(shot[0::2, :2] - shot[1::2, :2]) > 0.0)


def test_only_timing_on_the_error_is_rate_times_the_time_tag_error(campaign):
    _, table = campaign
    shift = _err(_cell(table, "timing")) - _err(_cell(table, "baseline"))  # same frames, other time tag
    expected = RATE_DEG_S * 3600.0 * TIMING_S  # 36 arcsec about camera x
    np.testing.assert_allclose(np.abs(shift[:, 0]), expected, atol=0.01)
    np.testing.assert_allclose(shift[:, 1:], 0.0, atol=0.01)


def test_only_aberration_on_the_boresight_moves_by_the_aberration_of_the_velocity(campaign):
    _, table = campaign
    cell, base = _cell(table, "aberration"), _cell(table, "baseline")
    axis = radec_to_vector(np.radians(cell["ra_deg"]), np.radians(cell["dec_deg"]))
    expected = angle_between(axis, aberrate(axis, [0.0, 0.0, SPEED_KM_S * 1e3])) / ARCSEC  # up to 68.8 arcsec
    shift = _err(cell) - _err(base)
    np.testing.assert_allclose(np.hypot(shift[:, 0], shift[:, 1]), expected, atol=0.3)
    assert expected.max() > 20.0


def test_proper_motion_and_distortion_on_move_the_solution(campaign):
    _, table = campaign
    base = _err(_cell(table, "baseline"))
    for source in ("proper_motion", "distortion"):  # k1 = 0.5 moves the field corners by 0.6 px
        assert np.max(np.abs(_err(_cell(table, source)) - base)) > 0.5, source


def test_the_report_and_the_text_show_the_budget(campaign):
    out, _ = campaign
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "<h2>Error budget</h2>" in page and "figures/budget.png" in page
    assert (out / "figures" / "budget.png").stat().st_size > 10_000
    csv = (out / "data" / "budget.csv").read_text(encoding="utf-8").splitlines()
    assert len(csv) == 1 + 8 + 1 and csv[0].startswith("case,source,cell,n_used")
    text = budget_text(out)
    timing = next(line for line in text.splitlines() if line.strip().startswith("timing"))
    assert float(timing.split()[2]) == pytest.approx(RATE_DEG_S * 3600.0 * TIMING_S, abs=0.05)  # cross bias
    assert "timing: off = exact time tag; on = time tag off by 0.05 s at [0.2, 0, 0] deg/s" in text


def test_rerun_reproduces_a_trial_of_a_shared_attitude(campaign):
    out, _ = campaign
    again = rerun_trial(out, 2, 5)
    assert again.same is True and math.isfinite(again.row["err_total_arcsec"])
