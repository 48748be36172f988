"""``startrack campaign``: run, report, rerun, list, and refusals (exit 2, one line, no work)."""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from cli_runner import run
from startrack.analysis.campaign import list_specs

SPEC = """
[campaign]
name = "cli-small"
level = "stars"
trials = 6
seed = 3
[base]
max_mag = 6.0
[sweep]
fov_deg = [12.0, 18.0]
"""


@pytest.fixture(scope="module")
def campaign(tmp_path_factory) -> tuple[Path, str]:
    folder = tmp_path_factory.mktemp("cli")
    spec = folder / "small.toml"
    spec.write_text(SPEC)
    code, out, err = run("campaign", "run", spec, "--sync", "--out", folder / "out")
    assert code == 0, err
    return folder / "out", out


def test_run_writes_the_folder_and_prints_a_line_per_cell(campaign):
    out, printed = campaign
    assert (out / "manifest.json").is_file() and (out / "cells.csv").is_file() and (out / "report.html").is_file()
    assert pq.read_table(out / "trials").num_rows == 12
    lines = printed.splitlines()
    assert any(line.startswith("0 fov_deg=12") for line in lines)
    assert any(line.startswith("1 fov_deg=18") for line in lines)
    assert "success [95 % CI]" in printed and f"report: {out / 'report.html'}" in printed


def test_rerun_json_gives_the_stored_row(campaign):
    out, _ = campaign
    code, printed, err = run("campaign", "rerun", out, "--cell", 1, "--trial", 4, "--json")
    assert code == 0, err
    data = json.loads(printed)
    assert data["same_as_stored"] is True
    assert data["row"]["cell"] == 1 and data["row"]["trial"] == 4 and data["row"]["fov_deg"] == 18.0


def test_rerun_saves_the_star_list(campaign, tmp_path):
    out, _ = campaign
    code, printed, err = run("campaign", "rerun", out, "--cell", 0, "--trial", 0, "--save-image", tmp_path)
    assert code == 0, err
    assert "same as the stored row: yes" in printed
    rows = (tmp_path / "cell0-trial0.csv").read_text().splitlines()
    assert rows[0] == "x,y,flux,is_real,hip" and len(rows) > 3


def test_report_rewrites_the_report(campaign):
    out, _ = campaign
    (out / "report.html").unlink()
    code, printed, err = run("campaign", "report", out)
    assert code == 0, err
    assert (out / "report.html").is_file() and "cli-small" in printed


def test_list_names_the_shipped_specs_and_a_levels_parameters():
    code, printed, _ = run("campaign", "list")
    assert code == 0
    assert all(spec.name in printed for spec in list_specs())
    code, printed, _ = run("campaign", "list", "--params", "image")
    assert code == 0 and "detect_sigma" in printed and "read_noise_e" in printed


def _refused(result, *words):
    code, out, err = result
    assert code == 2 and out == "" and "Traceback" not in err
    line = err.strip().splitlines()[-1]
    assert line.startswith("startrack campaign: error: "), err
    for word in words:
        assert word in line, line


def test_refusals_name_the_problem(campaign, tmp_path):
    out, _ = campaign
    bad = tmp_path / "bad.toml"
    bad.write_text(SPEC.replace("max_mag = 6.0", "max_mag = \"bright\""))
    _refused(run("campaign", "run", bad, "--sync", "--out", tmp_path / "x"), "[base] max_mag")
    assert not (tmp_path / "x").exists()
    _refused(run("campaign", "run", "no-such-spec", "--sync"), "no-such-spec", "campaign list")
    code, _, err = run("campaign", "run", "no-such-spec", "--sync")
    assert "named after their source" not in err
    _refused(run("campaign", "run", "seed000-table4.2-ws-vs-mle", "--sync"), "seed000-table4.2-ws-vs-mle",
             "huffman2006-table4.2-ws-vs-mle", "named after their source now", "docs/references.md")
    good = tmp_path / "good.toml"
    good.write_text(SPEC)
    _refused(run("campaign", "run", good, "--sync", "--out", out), "already holds a campaign", "--resume")
    _refused(run("campaign", "run", good, "--workers", "0", "--out", tmp_path / "y"), "--workers")
    _refused(run("campaign", "rerun", out, "--cell", 9, "--trial", 0), "--cell must be in 0..1")
    _refused(run("campaign", "report", tmp_path), "not a campaign output folder")
    _refused(run("campaign", "list", "--params", "galaxies"), "unknown level")


def test_without_the_extra_the_command_names_it(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "distributed", None)   # as if Dask were not installed
    _refused(run("campaign", "list"), "startrack[campaign]")


def test_progress_draws_a_bar_on_a_terminal_and_plain_lines_elsewhere(monkeypatch):
    from startrack.cli._progress import ProgressBar

    class Stream(io.StringIO):
        def __init__(self, tty):
            super().__init__()
            self.tty = tty

        def isatty(self):
            return self.tty

    for tty in (True, False):
        stream = Stream(tty)
        monkeypatch.setattr(sys, "stderr", stream)
        bar = ProgressBar("  trials")
        for done in range(1, 101):
            bar(done, 100)
        text = stream.getvalue()
        if tty:
            assert "\r  trials [" in text and text.endswith("100/100\n")
        else:
            assert "\r" not in text and "[" not in text
            assert text.splitlines() == ["trials: 1/100"] + [f"trials: {k}/100" for k in range(10, 101, 10)]
