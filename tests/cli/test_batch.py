"""Batches of ``startrack solve`` and ``startrack detect``: several files or a folder in one
process, good and bad files mixed, one table line / JSON object per image, CSV, --jobs, the
summary on stderr, exit status (0 all done, 1 some not, 2 misuse). Real images of
../shared/realdata (linked into a temporary folder, never copied into the repository)."""

from __future__ import annotations

import csv
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_cli import assert_misuse, assert_no_traceback, run, strict_json

from startrack.cli._batch import IMAGE_SUFFIXES, _safe
from startrack.cli._batch_detect import CSV_COLUMNS as DETECT_COLUMNS
from startrack.cli._batch_solve import CSV_COLUMNS as SOLVE_COLUMNS

GOOD = ("crappy.jpg", "roof.jpg")
FOV = ("--fov-range-deg", 5, 35)  # the range test_cli's real-photo test loads too


@pytest.fixture(scope="module")
def folder(tmp_path_factory, realdata_dir: Path) -> Path:
    """Two real photos, a PNG cut after its signature, an empty JPEG and a text file (not an image
    by its name, so a folder leaves it out)."""
    root = tmp_path_factory.mktemp("batch")
    for name in GOOD:
        (root / name).symlink_to(realdata_dir / "smroid-cedar-solve" / name)
    (root / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"\x00" * 20)
    (root / "empty.jpg").write_bytes(b"")
    (root / "notes.txt").write_text("not an image\n")
    return root


BAD = ("broken.png", "empty.jpg")


def _json_lines(out: str) -> list[dict]:
    return [strict_json(line) for line in out.splitlines()]


def test_folder_solves_good_files_and_reports_bad_ones_on_their_line(folder):
    code, out, err = run("solve", folder, *FOV)
    assert_no_traceback(out, err)
    assert code == 1  # some not solved
    header, *lines = out.splitlines()
    assert header.split()[:2] == ["image", "status"]
    names = [Path(line.split()[0]).name for line in lines]
    assert names == sorted([*GOOD, *BAD])  # by name, notes.txt left out
    status = {Path(line.split()[0]).name: line.split()[1] for line in lines}
    assert status == {"broken.png": "error", "crappy.jpg": "solved", "empty.jpg": "error", "roof.jpg": "solved"}
    assert "4 images" in err and "2 solved, 2 not solved" in err
    for name in BAD:
        assert f"{folder / name}: " in err


def test_json_lines_match_single_image_solves(folder):
    code, out, err = run("solve", *(folder / n for n in (*GOOD, "broken.png")), *FOV, "--json")
    assert code == 1, err
    records = _json_lines(out)
    assert [Path(r["image"]).name for r in records] == [*GOOD, "broken.png"]  # the order given
    assert records[2]["status"] == "error" and records[2]["reason"]
    for record, name in zip(records[:2], GOOD, strict=True):
        single_code, single_out, _ = run("solve", folder / name, *FOV, "--json")
        single = strict_json(single_out)
        assert single_code == 0 and record["status"] == "ok"
        for key in ("ra_deg", "dec_deg", "roll_deg", "fov_deg", "n_detections"):
            assert record[key] == pytest.approx(single[key], abs=1e-9), key  # deg or a count
        assert [m["hip"] for m in record["matches"]] == [m["hip"] for m in single["matches"]]


def test_csv_has_a_row_per_image_and_exit_zero_when_all_solve(folder, tmp_path):
    out_csv = tmp_path / "solutions.csv"
    code, out, err = run("solve", *(folder / n for n in GOOD), *FOV, "--csv", out_csv)
    assert code == 0, err
    with open(out_csv, newline="") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
    assert tuple(reader.fieldnames) == SOLVE_COLUMNS
    assert [Path(r["image"]).name for r in rows] == list(GOOD)
    assert [r["constellation"] for r in rows] == ["Taurus", "Camelopardalis"]  # as astropy's get_constellation says
    for row in rows:
        assert row["status"] == "ok" and row["reason"] == ""
        assert int(row["n_matched"]) >= 10
        quat = [float(row[k]) for k in ("qx", "qy", "qz", "qw")]
        assert math.isclose(sum(q * q for q in quat), 1.0, abs_tol=1e-9)  # a unit quaternion
    assert "2 solved, 0 not solved" in err


def test_jobs_give_the_serial_records(folder):
    serial = _json_lines(run("solve", folder, *FOV, "--json")[1])
    code, out, err = run("solve", folder, *FOV, "--json", "--jobs", 2)
    assert code == 1, err
    parallel = _json_lines(out)
    for a, b in zip(serial, parallel, strict=True):
        assert {k: v for k, v in a.items() if k != "solve_time_s"} == \
               {k: v for k, v in b.items() if k != "solve_time_s"}


def test_missing_file_and_size_limit_are_reported_per_image(folder):
    code, out, err = run("solve", folder / "roof.jpg", folder / "missing.png", *FOV, "--max-pixels", 1000)
    assert code == 1, err
    records = dict(line.split(maxsplit=1) for line in out.splitlines()[1:])
    assert "over the limit of 1,000 px" in records[str(folder / "roof.jpg")]
    assert "no such file or folder" in records[str(folder / "missing.png")]


def test_single_image_max_pixels_is_misuse(folder):
    assert_misuse(run("solve", folder / "roof.jpg", "--max-pixels", 1000), "solve", "over the limit")


def test_batch_misuse_exits_two(tmp_path, folder):
    assert_misuse(run("solve", tmp_path, *FOV), "solve", "holds no image files")
    assert_misuse(run("solve", folder, *FOV, "--wcs", tmp_path / "x.wcs"), "solve", "--wcs")
    assert_misuse(run("detect", tmp_path), "detect", "holds no image files")
    assert not list(tmp_path.iterdir())  # nothing written


def test_detect_batch_lines_json_and_per_star_csv(folder, tmp_path):
    out_csv = tmp_path / "stars.csv"
    code, out, err = run("detect", folder, "--json", "--csv", out_csv, "--max-stars", 5)
    assert_no_traceback(out, err)
    assert code == 1  # two files could not be read
    records = {Path(r["image"]).name: r for r in _json_lines(out)}
    assert sorted(records) == sorted([*GOOD, *BAD])
    assert all(records[n]["status"] == "error" and records[n]["reason"] for n in BAD)
    assert all(records[n]["status"] == "ok" and records[n]["n_stars"] == 5 for n in GOOD)
    with open(out_csv, newline="") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
    assert tuple(reader.fieldnames) == DETECT_COLUMNS
    assert len(rows) == 10  # 5 stars from each good image
    first = next(r for r in rows if Path(r["image"]).name == "roof.jpg")
    assert float(first["x"]) == pytest.approx(records["roof.jpg"]["stars"][0]["x"], abs=1e-9)  # px
    assert "2 done, 2 not done" in err


def test_detect_batch_table_exit_zero(folder):
    code, out, err = run("detect", *(folder / n for n in GOOD), "--jobs", 2)
    assert code == 0, err
    lines = out.splitlines()
    assert len(lines) == 3 and all(line.split()[1] == "ok" for line in lines[1:])


def test_folder_suffixes_cover_every_reader():
    assert {".fits", ".png", ".jpg", ".jpeg", ".tif", ".tiff", ".dng"} <= IMAGE_SUFFIXES


def test_csv_to_stdout_is_the_only_output(folder):
    code, out, err = run("solve", *(folder / n for n in GOOD), *FOV, "--csv", "-")
    assert code == 0, err
    rows = list(csv.DictReader(out.splitlines()))
    assert [Path(r["image"]).name for r in rows] == list(GOOD)
    assert all(r["status"] == "ok" for r in rows)


def test_a_fault_on_one_image_is_its_error_line(tmp_path):
    """Any exception one image raises (not only the expected input errors) becomes that image's
    error record, named as a fault, so that the batch goes on."""
    image = tmp_path / "a.png"
    image.write_bytes(b"")

    def faulty(path):
        raise KeyError(279)

    record = _safe(faulty, image)
    assert record["status"] == "error"
    assert "unexpected KeyError" in record["reason"] and "279" in record["reason"]


def test_csv_escapes_a_file_name_that_is_not_utf8(folder, tmp_path):
    """A file name whose bytes are not UTF-8 (held by Python as surrogates) is written to the CSV
    with backslash escapes; before, it stopped the whole batch and no CSV was written."""
    images = tmp_path / "names"
    images.mkdir()
    odd = images / os.fsdecode(b"bad\xff.jpg")
    odd.symlink_to(folder / GOOD[0])
    (images / GOOD[1]).symlink_to(folder / GOOD[1])
    out_csv = tmp_path / "stars.csv"
    code, out, err = run("detect", images, "--csv", out_csv, "--max-stars", 2)
    assert code == 0, err
    with open(out_csv, newline="", encoding="utf-8") as fh:
        names = {Path(r["image"]).name for r in csv.DictReader(fh)}
    assert names == {"bad\\udcff.jpg", GOOD[1]}


def _first_line_then_close(*argv) -> tuple[int, str]:
    """Run ``startrack ARGV`` in a new process, read its first output line and close the pipe
    (as ``| head -1`` does); its exit status and that line."""
    with subprocess.Popen([sys.executable, "-m", "startrack", *map(str, argv)], stdout=subprocess.PIPE,
                          stderr=subprocess.DEVNULL, text=True) as proc:
        first = proc.stdout.readline()
        proc.stdout.close()
        return proc.wait(timeout=300), first


def test_closed_output_stops_quietly_but_a_csv_is_still_written(folder, tmp_path):
    """``startrack detect A B --csv OUT | head -1``: OUT has every image's rows (before, the broken
    pipe was blamed on OUT, and OUT was dropped); without --csv the command stops with 141."""
    many = [folder / GOOD[i % 2] for i in range(6)]
    out_csv = tmp_path / "stars.csv"
    code, first = _first_line_then_close("detect", *many, "--csv", out_csv, "--max-stars", 1)
    assert first.split()[:2] == ["image", "status"]
    assert code == 0
    with open(out_csv, newline="") as fh:
        assert len(list(csv.DictReader(fh))) == len(many)  # one star from each
    code, _ = _first_line_then_close("detect", *many, "--max-stars", 1)
    assert code == 141


def test_an_interruption_inside_compiled_code_stops_the_batch(tmp_path):
    """Ctrl-C or SIGTERM inside a compiled function comes back as a SystemError whose cause is the
    interruption: the batch stops, rather than writing an error line and going on."""
    image = tmp_path / "a.png"
    image.write_bytes(b"")

    def interrupted(path):
        raise SystemError("CPUDispatcher returned a result with an exception set") from KeyboardInterrupt()

    with pytest.raises(KeyboardInterrupt):
        _safe(interrupted, image)
