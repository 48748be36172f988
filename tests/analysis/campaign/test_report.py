"""The report folder: cells.csv, every figure and the CSV behind it, report.html referencing them,
the reference tables, registered sections, the worst trials with their rerun commands; budget
mode and unfinished campaigns; a real (synchronous) campaign; no half-written page."""

from __future__ import annotations

import csv
import re
import shlex

import numpy as np
import pytest
from synthetic_campaign import BAD, GOOD, cell_rows, make_manifest, synthetic_campaign, write_campaign

from startrack.analysis.campaign import _report as report_module
from startrack.analysis.campaign._aggregate import read_campaign
from startrack.analysis.campaign._figures import report_figures
from startrack.analysis.campaign._report import SECTIONS, register_section, rerun_command, write_report
from startrack.analysis.campaign._run import run_campaign

SWEEP = {"fov_deg": [10.0, 20.0], "centroid_sigma_px": [0.1, 0.5]}
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    manifest, per_cell = synthetic_campaign(out, SWEEP, trials=50, n_error=2, p_false=0.06, stages=True,
                                            reference=[GOOD, BAD], name="report-test")
    seen = []

    def budget_like(manifest_arg, trials_arg, out_arg):
        seen.append((manifest_arg["name"], trials_arg.num_rows, out_arg))
        return "<h2>Extra section</h2><p>from a registered function</p>"

    def broken(manifest_arg, trials_arg, out_arg):
        raise RuntimeError("a broken section")

    register_section(budget_like)
    register_section(budget_like)  # registering twice adds it once
    register_section(broken)
    try:
        path = write_report(out)
    finally:
        SECTIONS.remove(budget_like)
        SECTIONS.remove(broken)
    return out, path, path.read_text(encoding="utf-8"), per_cell, seen


def test_every_file_is_written_and_referenced(written):
    out, path, page, _, _ = written
    assert path == out / "report.html" and (out / "cells.csv").is_file()
    pngs = sorted(p.relative_to(out).as_posix() for p in (out / "figures").glob("*.png"))
    assert {"figures/rates_by_fov_deg.png", "figures/accuracy_by_centroid_sigma_px.png", "figures/error_cdf.png",
            "figures/time.png", "figures/sky.png"} <= set(pngs)
    for png in pngs:
        assert (out / png).read_bytes()[:8] == PNG
    sources = re.findall(r'<img src="([^"]+)"', page)
    assert sorted(sources) == pngs  # every figure on the page, and only those
    links = re.findall(r'<a href="([^"]+)"', page)
    assert "cells.csv" in links and "data/by_fov_deg.csv" in links and "data/time-summary.csv" in links
    for link in links:
        assert (out / link).is_file(), link
    for csv_path in (out / "data").glob("*.csv"):
        with open(csv_path, newline="") as handle:
            assert len(list(csv.reader(handle))) >= 2, csv_path
    assert not list(out.rglob(".*.tmp"))


def test_the_page_is_self_contained(written):
    _, _, page, _, _ = written
    assert page.startswith("<!DOCTYPE html>") and "<style>" in page
    assert "<script" not in page and "http://" not in page and "https://" not in page


def test_spec_provenance_and_cells(written):
    _, _, page, _, _ = written
    assert "Campaign report-test" in page and "0.0.test" in page and "testhost" in page
    assert "fov_deg=20, centroid_sigma_px=0.5" in page and "has not finished" not in page


def test_reference_tables_on_the_page(written):
    out, _, page, _, _ = written
    assert "Ours beside the seed" in page and GOOD["title"] in page and "data/reference-0.csv" in page
    assert "Could not be evaluated" in page and "unknown aggregate" in page  # the broken one, not a crash


def test_registered_sections_are_called_with_the_campaign(written):
    out, _, page, _, seen = written
    assert seen == [("report-test", 200, out)]
    assert "<h2>Extra section</h2>" in page
    assert "broken failed: RuntimeError: a broken section" in page  # and the rest of the report is there
    assert page.index("Extra section") > page.index("Ours beside the seed")


def test_worst_trials_and_failures_with_their_rerun_commands(written):
    out, _, page, per_cell, _ = written
    err = np.concatenate([c["err_total_arcsec"] for c in per_cell])
    cell = np.concatenate([c["cell"] for c in per_cell])
    trial = np.concatenate([c["trial"] for c in per_cell])
    order = np.argsort(-np.where(np.isfinite(err), err, -np.inf))[:10]
    for i in order:
        assert rerun_command(out, int(cell[i]), int(trial[i])) in page.replace("&#x27;", "'")
    assert "FALSE SOLVE" in page  # false solves have the largest errors
    assert "RuntimeError: synthetic failure" in page and "Traceback" not in page
    for c in range(4):
        assert f"--cell {c} --trial 0" in page  # the ERROR rows are trials 0 and 1 of every cell


def test_rerun_command_quotes_the_folder(tmp_path):
    out = tmp_path / "my campaign"
    assert shlex.split(rerun_command(out, 3, 7)) == ["startrack", "campaign", "rerun", str(out), "--cell", "3",
                                                     "--trial", "7"]


def test_budget_mode_and_an_unfinished_campaign(tmp_path, monkeypatch):
    manifest, _ = synthetic_campaign(tmp_path, {}, trials=20, mode="budget", sources=["baseline", "all", "shot_noise"],
                                     finished=False)
    _, trials = read_campaign(tmp_path)
    figures, notes = report_figures(trials, manifest)  # built, not drawn: the drawing is tested above
    assert notes == []
    assert [f.name for f in figures][:2] == ["rates_by_cell", "accuracy_by_cell"]
    assert figures[0].data[""]["label"].to_pylist() == ["baseline", "all", "shot_noise"]
    monkeypatch.setattr(report_module, "report_figures", lambda trials, manifest: ([], []))
    page = write_report(tmp_path).read_text(encoding="utf-8")
    assert "has not finished" in page and "shot_noise" in page
    with open(tmp_path / "cells.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["source"] for r in rows] == ["baseline", "all", "shot_noise"]


def test_an_interrupted_report_leaves_the_previous_page(written, monkeypatch):
    out, path, first, _, _ = written

    def dies(fig, folder):
        raise KeyboardInterrupt

    monkeypatch.setattr(report_module, "save_figure", dies)
    with pytest.raises(KeyboardInterrupt):
        write_report(out)
    assert path.read_text(encoding="utf-8") == first
    assert not list(out.rglob(".*.tmp"))


def test_a_level_without_attitude_errors_and_stale_files(tmp_path):
    # levels such as starcount mark trials solved and correct but record no attitude error
    manifest = make_manifest({"fov_deg": [10.0, 20.0]}, 8)
    rng = np.random.default_rng(2)
    per_cell = [cell_rows(c, ["fov_deg"], 8, rng, p_correct=1.0, p_false=0.0) for c in manifest["cells"]]
    for cols in per_cell:
        for name in ("err_x_arcsec", "err_y_arcsec", "err_roll_arcsec", "err_cross_arcsec", "err_total_arcsec"):
            cols[name] = np.full(8, np.nan)
    write_campaign(tmp_path, manifest, per_cell)
    for stale in ("figures/accuracy_by_fov_deg.png", "data/reference-3.csv", "figures/budget.png"):
        (tmp_path / stale).parent.mkdir(exist_ok=True)
        (tmp_path / stale).write_bytes(b"old")
    page = write_report(tmp_path).read_text(encoding="utf-8")
    assert "No correct trial has an attitude error" in page
    assert sorted(p.name for p in (tmp_path / "figures").glob("*.png")) == ["budget.png", "rates_by_fov_deg.png",
                                                                            "sky.png", "time.png"]
    assert not (tmp_path / "data" / "reference-3.csv").exists()  # the report's own stale file goes
    assert (tmp_path / "figures" / "budget.png").read_bytes() == b"old"  # another module's file stays


REAL = """
[campaign]
name = "report-real"
level = "stars"
trials = 6
seed = 11
[base]
max_mag = 6.0
[sweep]
fov_deg = [12.0, 20.0]
[[reference]]
title = "success"
metric = "rate:correct"
rows = [ { where = { fov_deg = 20.0 }, seed = 1.0 } ]
"""


def test_a_real_campaign_gets_its_report(tmp_path):
    out = tmp_path / "real"
    trials = run_campaign(REAL, out, sync=True)
    page = (out / "report.html").read_text(encoding="utf-8")
    with open(out / "cells.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["fov_deg"] for r in rows] == ["12", "20"] and [int(r["n"]) for r in rows] == [6, 6]
    assert int(rows[1]["n_correct"]) == sum(trials.filter(trials["cell"].to_numpy() == 1)["correct"].to_pylist())
    assert "figures/sky.png" in page and "Ours beside the seed" in page
