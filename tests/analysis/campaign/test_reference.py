"""Reference tables (ours beside the seed's): the rows pick the right cells and compute the right
metric over their pooled trials; bad metrics and selections are refused naming the problem."""

from __future__ import annotations

import math

import numpy as np
import pytest
from synthetic_campaign import BAD, GOOD, synthetic_campaign

from startrack.analysis.campaign._aggregate import read_campaign
from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._reference import (
    check_references,
    evaluate_reference,
    match_cells,
    reference_tables,
    reference_text,
)
from startrack.analysis.campaign._spec import parse_spec
from startrack.errors import InvalidInputError

SWEEP = {"fov_deg": [10.0, 20.0], "centroid_sigma_px": [0.1, 0.5]}


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref")
    manifest, per_cell = synthetic_campaign(out, SWEEP, trials=50, reference=[GOOD, BAD])
    _, trials = read_campaign(out)
    return out, manifest, per_cell, trials


def test_rows_pick_the_cells_and_compute_the_metric(campaign):
    _, manifest, per_cell, trials = campaign
    rows = evaluate_reference(GOOD, trials, manifest).table.to_pylist()
    # row 0: cells 0 and 1 pooled, p95 of the cross error of their correct trials
    pooled = np.concatenate([c["err_cross_arcsec"][c["correct"]] for c in per_cell[:2]])
    assert rows[0]["cells"] == "0,1" and rows[0]["n_trials"] == 100 and rows[0]["n_used"] == pooled.size
    assert rows[0]["ours"] == pytest.approx(np.percentile(pooled, 95), rel=1e-12)
    assert rows[0]["difference"] == pytest.approx(rows[0]["ours"] - 2.5, rel=1e-12)
    assert rows[0]["ratio"] == pytest.approx(rows[0]["ours"] / 2.5, rel=1e-12)
    assert (rows[0]["label"], rows[0]["note"]) == ("FOV 10", "both noises")
    # row 1: one cell, the seed gives text: no difference
    assert rows[1]["cells"] == "3" and rows[1]["seed"] == "n/a" and math.isnan(rows[1]["difference"])
    assert rows[1]["label"] == "fov_deg=20, centroid_sigma_px=0.5"
    # row 2: a list matches any of its values; the row's own metric
    correct = np.concatenate([c["correct"] for c in per_cell[2:]])
    assert rows[2]["cells"] == "2,3" and rows[2]["ours"] == pytest.approx(correct.mean(), rel=1e-12)
    # row 3: every cell; a zero seed has no ratio
    assert rows[3]["cells"] == "0,1,2,3" and rows[3]["label"] == "all cells"
    assert rows[3]["ours"] == min(int(c["n_stars"].min()) for c in per_cell) and math.isnan(rows[3]["ratio"])


def test_scale_turns_ours_into_the_seeds_unit(campaign):
    _, manifest, _, trials = campaign
    plain = evaluate_reference(GOOD, trials, manifest).table["ours"].to_pylist()[0]
    scaled = evaluate_reference({**GOOD, "scale": 1 / 60}, trials, manifest).table["ours"].to_pylist()[0]
    assert scaled == pytest.approx(plain / 60, rel=1e-12)


def test_match_cells(campaign):
    _, manifest, _, _ = campaign
    assert match_cells(manifest, {"centroid_sigma_px": 0.1}) == [0, 2]
    assert match_cells(manifest, {"fov_deg": 10.000000000001}) == [0, 1]  # numbers to 1e-9 relative
    assert match_cells(manifest, {"fov_range_deg": [5.0, 35.0]}) == [0, 1, 2, 3]  # a list parameter is a value
    assert match_cells(manifest, {"label": "fov_deg=20, centroid_sigma_px=0.1"}) == [2]
    assert match_cells(manifest, {"fov_deg": 15.0}) == []
    with pytest.raises(InvalidInputError, match="where fov: not a parameter"):
        match_cells(manifest, {"fov": 10.0})


@pytest.mark.parametrize(("reference", "problem"), [
    (BAD, "unknown aggregate 'average'"),
    ({**GOOD, "metric": "p95:err_crosss_arcsec"}, "no trials column 'err_crosss_arcsec'"),
    ({**GOOD, "rows": [{"where": {"fov_deg": 15.0}, "seed": 1}]}, "row 0 (fov_deg=15): where {'fov_deg': 15.0} "
                                                                   "selects no cell"),
    ({**GOOD, "rows": [{"where": {"fvo_deg": 10.0}, "seed": 1}]}, "where fvo_deg: not a parameter"),
    ({**GOOD, "rows": "all"}, "rows must be a list"),
    ({**GOOD, "rows": [3]}, "row 0: must be a table"),
])
def test_bad_references_are_refused_naming_the_problem(campaign, reference, problem):
    _, manifest, _, trials = campaign
    with pytest.raises(InvalidInputError) as info:
        evaluate_reference(reference, trials, manifest)
    assert problem in str(info.value) and repr(reference["title"]) in str(info.value)


def test_reference_tables_strict_and_lenient(campaign):
    _, manifest, _, trials = campaign
    with pytest.raises(InvalidInputError, match="broken"):
        reference_tables(trials, manifest)
    refs = reference_tables(trials, manifest, strict=False)
    assert [r.title for r in refs] == [GOOD["title"], "broken"]
    assert refs[0].error == "" and refs[0].table.num_rows == 4
    assert "unknown aggregate" in refs[1].error and refs[1].table.num_rows == 0


def test_reference_text(campaign):
    out, manifest, _, trials = campaign
    text = reference_text(out)
    ours = evaluate_reference(GOOD, trials, manifest).table["ours"].to_pylist()[0]
    assert GOOD["title"] in text and "metric: p95:err_cross_arcsec (arcsec)" in text
    line = next(line for line in text.splitlines() if line.strip().startswith("FOV 10"))
    assert f"{ours:.4g}" in line and "2.5" in line and line.rstrip().endswith("100")
    assert "FOV 10: both noises" in text
    assert "could not be evaluated" in text and "average" in text


def test_reference_text_is_empty_without_references(tmp_path):
    synthetic_campaign(tmp_path, {"fov_deg": [10.0]}, trials=4)
    assert reference_text(tmp_path) == ""


def test_check_references_before_any_work(campaign):
    _, manifest, _, _ = campaign
    check_references([GOOD], manifest["cells"])
    with pytest.raises(InvalidInputError, match="'broken': metric 'average:err_cross_arcsec': unknown aggregate"):
        check_references([GOOD, BAD], manifest["cells"])
    bad_row_metric = {**GOOD, "rows": [{"where": {}, "seed": 1, "metric": "p95"}]}
    with pytest.raises(InvalidInputError, match="metric 'p95': write AGG:COLUMN"):
        check_references([bad_row_metric], manifest["cells"])
    with pytest.raises(InvalidInputError, match="scale must be a finite number"):
        check_references([{**GOOD, "scale": "1/60"}], manifest["cells"])
    with pytest.raises(InvalidInputError, match="selects no cell"):
        check_references([{**GOOD, "rows": [{"where": {"fov_deg": 30.0}}]}], manifest["cells"])
    spec = parse_spec(SPEC_WITH_REFERENCE)
    check_references(spec.reference, spec.cells())  # spec.Cell objects
    with pytest.raises(InvalidInputError, match="where max_mag: not a parameter"):
        check_references([{**GOOD, "rows": [{"where": {"max_mag": 6.0}}]}], spec.cells()[:0])


SPEC_WITH_REFERENCE = """
[campaign]
name = "check"
[sweep]
fov_deg = [10.0, 20.0]
[[reference]]
title = "t"
metric = "rate:correct"
rows = [ { where = { fov_deg = 20.0 }, seed = 1 } ]
"""


def test_a_bad_reference_in_a_spec_is_named_once():
    """The spec's check prefixed '[[reference]]' to a message that names the reference already."""
    bad = SPEC_WITH_REFERENCE.replace('metric = "rate:correct"', 'metric = "nonsense:foo"')
    with pytest.raises(SpecError) as info:
        parse_spec(bad)
    assert str(info.value).startswith("[[reference]] 't': metric 'nonsense:foo'")
    assert str(info.value).count("[[reference]]") == 1


def test_the_summary_of_an_unfinished_campaign_says_how_far_it_got(tmp_path):
    """It printed '7000 trials in 1 cells on not run' for a run stopped at 7000 of 100000."""
    from startrack.analysis.campaign._summary import summary_text

    synthetic_campaign(tmp_path, {"fov_deg": [10.0, 20.0], "centroid_sigma_px": [0.1]}, trials=40, finished=False)
    next((tmp_path / "trials").glob("part-00001-*.parquet")).unlink()  # half of cell 1 never ran
    head = summary_text(tmp_path).splitlines()[0]
    assert "60 of 80 trials in 2 cells, a run that did not finish (--resume finishes it)" in head
