"""Damaged campaign folders: ``report``, ``rerun`` and ``run --resume`` refuse them with exit 2 and one
line naming the damaged file and what to do (never exit 3), and a refused command changes no file.

One small real campaign (the spec of tests/cli/test_campaign_cmd.py) is run once; each test damages
a copy of it.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from cli_runner import run

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
PART = "part-00000-000000.parquet"
AGAIN = "run the spec again into a new --out folder"


@pytest.fixture(scope="module")
def good(tmp_path_factory) -> tuple[Path, Path]:
    """A finished campaign folder and its spec file."""
    folder = tmp_path_factory.mktemp("good")
    spec = folder / "ok.toml"
    spec.write_text(SPEC)
    code, _, err = run("campaign", "run", spec, "--sync", "--out", folder / "out")
    assert code == 0, err
    return folder / "out", spec


def damaged(good: tuple[Path, Path], tmp_path: Path, damage: Callable[[Path], None]) -> Path:
    """A copy of the good folder with ``damage`` done to it."""
    out = tmp_path / "x"
    shutil.copytree(good[0], out)
    damage(out)
    return out


def snapshot(folder: Path) -> dict[str, tuple[int, bytes]]:
    """Every file under ``folder``: modification time and content."""
    return {p.relative_to(folder).as_posix(): (p.stat().st_mtime_ns, p.read_bytes())
            for p in sorted(folder.rglob("*")) if p.is_file()}


def commands(out: Path, spec: Path) -> dict[str, list[object]]:
    return {"report": ["campaign", "report", out], "rerun": ["campaign", "rerun", out, "--cell", 0, "--trial", 0],
            "resume": ["campaign", "run", spec, "--out", out, "--resume", "--sync"]}


def refused(argv: list[object], out: Path, *words: str) -> str:
    """Run ``argv``; check exit 2, one error line holding ``words``, no traceback, no file changed."""
    before = snapshot(out)
    code, printed, err = run(*argv)
    line = err.strip().splitlines()[-1] if err.strip() else ""
    assert code == 2, err
    assert "Traceback" not in err and printed == ""
    assert line.startswith("startrack campaign: error: "), err
    for word in words:
        assert word in line, line
    assert snapshot(out) == before  # nothing written, not even in part
    return line


def garbage_part(out: Path) -> None:
    (out / "trials" / PART).write_text("garbage\n")


def part_without_status(out: Path) -> None:
    path = out / "trials" / PART
    pq.write_table(pq.read_table(path).drop_columns(["status"]), path)


def part_with_string_cells(out: Path) -> None:
    path = out / "trials" / PART
    table = pq.read_table(path)
    cells = pa.array([str(c) for c in table["cell"].to_pylist()])
    pq.write_table(table.set_column(table.schema.get_field_index("cell"), "cell", cells), path)


def edit_manifest(**changes: object) -> Callable[[Path], None]:
    def damage(out: Path) -> None:
        manifest = json.loads((out / "manifest.json").read_text())
        manifest.update(changes)
        (out / "manifest.json").write_text(json.dumps(manifest))
    return damage


def write_manifest(text: str) -> Callable[[Path], None]:
    def damage(out: Path) -> None:
        (out / "manifest.json").write_text(text)
    return damage


def drop_manifest_key(key: str) -> Callable[[Path], None]:
    def damage(out: Path) -> None:
        manifest = json.loads((out / "manifest.json").read_text())
        del manifest[key]
        (out / "manifest.json").write_text(json.dumps(manifest))
    return damage


COMMANDS = ("report", "rerun", "resume")


@pytest.mark.parametrize("command", COMMANDS)
def test_a_garbage_part_is_named_with_what_to_do(good, tmp_path, command):
    out = damaged(good, tmp_path, garbage_part)
    line = refused(commands(out, good[1])[command], out, str(out / "trials" / PART), "not a readable Parquet file",
                   "remove it", "--resume", AGAIN)
    assert "ArrowInvalid" not in line and "fault of startrack" not in line


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize(("damage", "words"), [
    (part_without_status, ("has no column 'status'",)),
    (part_with_string_cells, ("column 'cell' is string, expected integer",)),
], ids=["missing-column", "wrong-type"])
def test_a_part_of_another_shape_is_named(good, tmp_path, command, damage, words):
    out = damaged(good, tmp_path, damage)
    refused(commands(out, good[1])[command], out, str(out / "trials" / PART), "remove it", *words)


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize(("damage", "words"), [
    (write_manifest("[]\n"), ("must hold a JSON object", "got a list", AGAIN)),
    (write_manifest("not json {\n"), ("is not valid UTF-8 JSON", AGAIN)),
    (lambda out: (out / "manifest.json").write_bytes(b"\xff\xfe\x00\x81"), ("is not valid UTF-8 JSON",)),
    (write_manifest("\"just a string\"\n"), ("must hold a JSON object", "got a string")),
    (edit_manifest(spec=None), ("is damaged: spec must be an object, got null", AGAIN)),
    (edit_manifest(cells=[{"cell": 0, "params": None}]), ("cells[0].params must be an object, got null",)),
    (edit_manifest(cells="two"), ("cells must be a list, got a string",)),
    (edit_manifest(spec_text=3), ("spec_text must be a string, got an integer",)),
    (edit_manifest(chunk_size=0), ("chunk_size must be at least 1, got 0",)),
    (edit_manifest(trials_per_cell=True), ("trials_per_cell must be an integer, got true",)),
    (edit_manifest(runs=[None]), ("runs[0] must be an object, got null",)),
    (drop_manifest_key("cells"), ("cells is missing (it must be a list)",)),
    (edit_manifest(format="startrack-campaign/9"), ("format 'startrack-campaign/9', expected 'startrack-campaign/1'",)),
], ids=["list", "not-json", "binary", "string", "spec-null", "params-null", "cells-string", "spec-text-int", "chunk-0",
        "trials-bool", "run-null", "no-cells", "format"])
def test_a_manifest_of_the_wrong_shape_is_refused_alike(good, tmp_path, command, damage, words):
    out = damaged(good, tmp_path, damage)
    refused(commands(out, good[1])[command], out, str(out / "manifest.json"), *words)


@pytest.mark.parametrize("command", COMMANDS)
def test_a_missing_manifest_beside_parts_is_called_damage(good, tmp_path, command):
    out = damaged(good, tmp_path, lambda out: (out / "manifest.json").unlink())
    refused(commands(out, good[1])[command], out, f"{out} is damaged", "no manifest.json", AGAIN)


@pytest.mark.parametrize("command", ["report", "rerun"])
def test_a_folder_without_a_campaign_is_no_campaign_folder(tmp_path, command):
    (tmp_path / "x").mkdir()
    refused(commands(tmp_path / "x", tmp_path / "ok.toml")[command], tmp_path / "x",
            "is not a campaign output folder", "no readable manifest.json")


def test_report_of_spec_null_changes_no_file(good, tmp_path):
    # it used to rewrite cells.csv and data/ and then crash, leaving report.html stale
    out = damaged(good, tmp_path, edit_manifest(spec=None))
    for name in ("cells.csv", "data/status.csv", "report.html"):
        (out / name).write_text("before")
    refused(["campaign", "report", out], out, "spec must be an object")
    assert all((out / name).read_text() == "before" for name in ("cells.csv", "data/status.csv", "report.html"))


@pytest.mark.parametrize("emptied", ["empty", "missing"])
def test_without_trial_parts_report_refuses_rerun_and_resume_work(good, tmp_path, emptied):
    def damage(out: Path) -> None:
        shutil.rmtree(out / "trials")
        if emptied == "empty":
            (out / "trials").mkdir()
    out = damaged(good, tmp_path, damage)
    refused(commands(out, good[1])["report"], out, "no finished trials yet")
    code, printed, err = run(*commands(out, good[1])["rerun"])
    assert code == 0, err
    assert "same as the stored row: not stored" in printed
    code, printed, err = run(*commands(out, good[1])["resume"], "--no-report")
    assert code == 0, err
    assert pq.read_table(out / "trials").num_rows == 12  # every chunk ran again
    assert "12 trials in 2 cells" in printed


def test_a_trials_file_is_refused(good, tmp_path):
    def damage(out: Path) -> None:
        shutil.rmtree(out / "trials")
        (out / "trials").write_text("not a folder")
    out = damaged(good, tmp_path, damage)
    for argv in commands(out, good[1]).values():
        refused(argv, out, str(out / "trials"), "is not a folder")
