"""The cells table and the numbers behind the figures, on synthetic campaign folders, against
aggregates computed here with numpy from the same columns."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest
from synthetic_campaign import synthetic_campaign

from startrack.analysis.campaign._aggregate import (
    axis_table,
    cell_table,
    quantile_table,
    read_campaign,
    sky_table,
    status_table,
    time_tables,
    write_cells_csv,
)
from startrack.analysis.campaign._stats import rate_upper_bound, wilson_interval
from startrack.errors import InvalidInputError

SWEEP = {"fov_deg": [10.0, 20.0], "centroid_sigma_px": [0.1, 0.5]}


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("agg")
    manifest, per_cell = synthetic_campaign(out, SWEEP, trials=60, n_error=3, p_false=0.05, stages=True)
    _, trials = read_campaign(out)
    return out, manifest, per_cell, trials


def test_cell_table_against_numpy(campaign):
    _, manifest, per_cell, trials = campaign
    table = cell_table(trials, manifest).to_pylist()
    assert [r["cell"] for r in table] == [0, 1, 2, 3]
    assert [(r["fov_deg"], r["centroid_sigma_px"]) for r in table] == [(10, 0.1), (10, 0.5), (20, 0.1), (20, 0.5)]
    for row, cols in zip(table, per_cell, strict=True):
        correct, solved = cols["correct"], cols["solved"]
        n_false = int((solved & ~correct).sum())
        assert (row["n"], row["n_error"], row["n_correct"], row["n_false"]) == (60, 3, correct.sum(), n_false)
        assert row["success_rate"] == pytest.approx(correct.mean(), abs=1e-15)
        assert (row["success_low"], row["success_high"]) == wilson_interval(int(correct.sum()), 60)
        assert row["false_upper"] == rate_upper_bound(n_false, 60)
        good_cross = cols["err_cross_arcsec"][correct]
        good_roll = np.abs(cols["err_roll_arcsec"][correct])
        for q, name in ((50, "p50"), (68, "p68"), (95, "p95"), (99.7, "p99_7")):
            assert row[f"err_cross_{name}_arcsec"] == pytest.approx(np.percentile(good_cross, q), rel=1e-12)
            assert row[f"err_roll_{name}_arcsec"] == pytest.approx(np.percentile(good_roll, q), rel=1e-12)
        assert row["err_x_mean_arcsec"] == pytest.approx(cols["err_x_arcsec"][correct].mean(), rel=1e-12)
        assert row["err_roll_std_arcsec"] == pytest.approx(cols["err_roll_arcsec"][correct].std(ddof=1), rel=1e-12)
        ran = cols["time_s"][3:]  # the three ERROR rows have no time
        assert row["time_p95_s"] == pytest.approx(np.percentile(ran, 95), rel=1e-12)
        assert row["time_max_s"] == pytest.approx(ran.max(), rel=1e-12)
        assert row["time_detect_p50_s"] == pytest.approx(np.median(ran * 0.4), rel=1e-12)
        assert row["n_matched_mean"] == pytest.approx(cols["n_matched"][solved].mean(), rel=1e-12)
        assert row["n_stars_mean"] == pytest.approx(cols["n_stars"][3:].mean(), rel=1e-12)


def test_false_solves_stay_out_of_the_error_percentiles(campaign):
    _, manifest, per_cell, trials = campaign
    assert any((c["solved"] & ~c["correct"]).any() for c in per_cell)  # the synthetic set has false solves
    table = cell_table(trials, manifest)
    assert max(table["err_cross_p99_7_arcsec"].to_pylist()) < 100  # a false solve is 18,000 arcsec off


def test_a_cell_without_trials_yet(tmp_path):
    manifest, _ = synthetic_campaign(tmp_path, {"fov_deg": [10.0, 20.0]}, trials=10)
    (tmp_path / "trials" / "part-00001-000000.parquet").unlink()
    (tmp_path / "trials" / "part-00001-000005.parquet").unlink()
    manifest_read, trials = read_campaign(tmp_path)
    rows = cell_table(trials, manifest_read).to_pylist()
    assert rows[1]["n"] == 0 and math.isnan(rows[1]["success_rate"]) and math.isnan(rows[1]["err_cross_p50_arcsec"])
    assert rows[0]["n"] == 10


def test_write_cells_csv(campaign):
    out, _, per_cell, _ = campaign
    path = write_cells_csv(out)
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 4 and rows[1]["label"] == "fov_deg=10, centroid_sigma_px=0.5"
    assert float(rows[2]["success_rate"]) == pytest.approx(per_cell[2]["correct"].mean(), rel=1e-9)
    assert not list(out.glob(".*.tmp"))


def test_read_campaign_refuses_a_folder_without_a_campaign(tmp_path):
    with pytest.raises(InvalidInputError, match="no readable manifest.json"):
        read_campaign(tmp_path)
    manifest, _ = synthetic_campaign(tmp_path, {"fov_deg": [10.0]}, trials=4)
    (tmp_path / "manifest.json").write_text(json.dumps({**manifest, "format": "startrack-campaign/9"}))
    with pytest.raises(InvalidInputError, match="format 'startrack-campaign/9', expected 'startrack-campaign/1'"):
        read_campaign(tmp_path)
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    for part in (tmp_path / "trials").glob("*.parquet"):
        part.unlink()
    with pytest.raises(InvalidInputError, match="no finished trials"):
        read_campaign(tmp_path)


def test_axis_table_lines_and_pooling(campaign, tmp_path):
    _, manifest, per_cell, trials = campaign
    table, line, note = axis_table(trials, manifest, "centroid_sigma_px")
    assert line == "fov_deg" and note == "" and table.num_rows == 4
    assert table.column_names[:2] == ["centroid_sigma_px", "fov_deg"]
    by_cell, line, _ = axis_table(trials, manifest, None)
    assert line is None and by_cell["label"].to_pylist()[0] == "fov_deg=10, centroid_sigma_px=0.1"
    sweep3 = {"fov_deg": [10.0, 20.0], "centroid_sigma_px": [0.1, 0.5], "max_mag": [5.0, 6.0]}
    manifest3, cols3 = synthetic_campaign(tmp_path, sweep3, trials=10)
    _, trials3 = read_campaign(tmp_path)
    pooled, line, note = axis_table(trials3, manifest3, "fov_deg")
    assert line is None and note == "pooled over centroid_sigma_px, max_mag"
    assert pooled["n"].to_pylist() == [40, 40]
    expected = sum(int(c["correct"].sum()) for c in cols3[:4])  # the fov 10 cells come first
    assert pooled["n_correct"].to_pylist()[0] == expected


def test_quantile_table_gives_the_percentiles_of_the_correct_trials(campaign):
    _, manifest, per_cell, trials = campaign
    table, split = quantile_table(trials, manifest)
    assert split == "cell"
    rows = [r for r in table.to_pylist() if r["curve"] == "fov_deg=20, centroid_sigma_px=0.5" and r["error"] == "roll"]
    ref = np.abs(per_cell[3]["err_roll_arcsec"][per_cell[3]["correct"]])
    by_percent = {r["percent"]: r["value_arcsec"] for r in rows}
    for q in (0.0, 50.0, 68.0, 99.7, 100.0):
        assert by_percent[q] == pytest.approx(np.percentile(ref, q), rel=1e-12)
    assert rows[0]["n"] == ref.size
    _, split = quantile_table(trials, manifest, max_curves=3)
    assert split.startswith("fov_deg")


def test_time_tables(campaign):
    _, _, per_cell, trials = campaign
    hist, summary = time_tables(trials)
    times = np.concatenate([c["time_s"][3:] for c in per_cell])
    assert int(hist["time_s"].to_numpy().sum()) == times.size
    assert hist.column_names == ["left_ms", "right_ms", "time_s", "time_s_solved", "time_s_unsolved", "time_detect_s",
                                 "time_identify_s"]
    solved = np.concatenate([c["solved"][3:] for c in per_cell])
    assert int(hist["time_s_solved"].to_numpy().sum()) == solved.sum()
    assert int(hist["time_s_unsolved"].to_numpy().sum()) == (~solved).sum()
    edges = np.append(hist["left_ms"].to_numpy(), hist["right_ms"].to_numpy()[-1])
    assert edges[0] <= times.min() * 1e3 and edges[-1] >= times.max() * 1e3
    first = summary.to_pylist()[0]
    assert first["time"] == "time_s" and first["n"] == times.size
    assert first["p99_ms"] == pytest.approx(np.percentile(times, 99) * 1e3, rel=1e-12)


def test_sky_bins_are_equal_area_and_count_every_trial(campaign):
    _, _, per_cell, trials = campaign
    sky = sky_table(trials, n_dec=6)
    assert sky.num_rows == 72
    area = ((np.sin(np.radians(sky["dec_hi_deg"].to_numpy())) - np.sin(np.radians(sky["dec_lo_deg"].to_numpy())))
            * (sky["ra_hi_deg"].to_numpy() - sky["ra_lo_deg"].to_numpy()))
    np.testing.assert_allclose(area, area[0], rtol=1e-12)
    assert sky["n"].to_numpy().sum() == 240
    ra, dec = per_cell[0]["ra_deg"][0], per_cell[0]["dec_deg"][0]
    hit = [r for r in sky.to_pylist()
           if r["ra_lo_deg"] <= ra < r["ra_hi_deg"] and r["dec_lo_deg"] <= dec < r["dec_hi_deg"]]
    assert len(hit) == 1 and hit[0]["n"] >= 1
    rows = sky.to_pylist()
    assert all(math.isnan(r["success_rate"]) == (r["n"] == 0) for r in rows)
    assert sum(r["n_correct"] for r in rows) == sum(int(c["correct"].sum()) for c in per_cell)


def test_status_table(campaign):
    _, manifest, per_cell, trials = campaign
    table = status_table(trials, manifest)
    assert table.column_names[:3] == ["cell", "label", "OK"]
    for row, cols in zip(table.to_pylist(), per_cell, strict=True):
        assert row["ERROR"] == 3 and row["OK"] == int(cols["solved"].sum())
        assert sum(v for k, v in row.items() if k not in ("cell", "label")) == 60
