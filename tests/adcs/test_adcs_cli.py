"""startrack adcs-demo: help, a short run with --json, the files, and misuse."""

from __future__ import annotations

import json

import pytest

from startrack.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_help_documents_the_output_and_the_exit_status(capsys):
    code, out, _ = run(capsys, "adcs-demo", "--help")
    assert code == 0 and out.startswith("usage: startrack adcs-demo")
    for words in ("exit status", "steady_state_error_deg", "--feedback", "--duration-s", "--json"):
        assert words in out


def test_short_truth_run_prints_json_with_the_metrics_and_writes_its_files(capsys, tmp_path):
    code, out, _ = run(capsys, "adcs-demo", "--feedback", "truth", "--duration-s", "30", "--out", str(tmp_path),
                       "--json")
    data = json.loads(out)
    assert code == 0 and data["meets_table_5_3"] is True
    assert data["feedback"] == "truth" and data["wall_time_s"] > 0
    keys = {"steady_state_error_deg", "overshoot_pct", "rise_time_s", "settling_time_s", "avg_power_w", "peak_power_w"}
    assert keys <= set(data["overall"]) and len(data["steps"]) == 1 and keys <= set(data["steps"][0])
    assert data["overall"]["rise_time_s"] < 8.0
    names = {p.rsplit("/", 1)[-1] for p in data["files"]}
    assert names == {"attitude.png", "actuation.png", "feedback.png", "run.csv", "summary.json"}
    assert (tmp_path / "attitude.png").stat().st_size > 10_000
    header = (tmp_path / "run.csv").read_text().splitlines()[0]
    assert header.startswith("t_s,theta_true,omega_true")
    assert len((tmp_path / "run.csv").read_text().splitlines()) == 30 * 40 + 1


def test_too_short_a_run_exits_1_and_says_so(capsys, tmp_path):
    code, out, _ = run(capsys, "adcs-demo", "--feedback", "truth", "--duration-s", "5", "--out", str(tmp_path))
    assert code == 1 and "does not meet the seed's Table 5.3" in out


@pytest.mark.parametrize(("argv", "words"), [
    (["--feedback", "tracker-model"], "--noise-model"),
    (["--field", "dipole"], "--plant three-axis"),
    (["--duration-s", "-3"], "duration_s"),
    (["--j22-kg-m2", "0"], "j22_kg_m2"),
    (["--frame-rate-hz", "50"], "frame period"),
])
def test_misuse_exits_2_with_one_line(capsys, tmp_path, argv, words):
    code, out, err = run(capsys, "adcs-demo", "--out", str(tmp_path), *argv)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and err.startswith("startrack adcs-demo: error: ") and words in err


def test_the_tracker_model_prints_its_table_without_a_processing_time(capsys, tmp_path):
    # the modelled tracker measures no processing time, and the text table multiplied its None by 1e3:
    # every `--feedback tracker-model` run without --json ended as an unexpected TypeError (exit 3)
    model = {"theta_bias_rad": 0.0, "theta_sigma_rad": 1e-3, "rate_sigma_rad_s": 1e-3, "rate_delay_s": 0.1,
             "latency_s": 0.1, "valid_fraction": 1.0, "frames": 10}
    (tmp_path / "noise.json").write_text(json.dumps(model))
    code, out, err = run(capsys, "adcs-demo", "--feedback", "tracker-model", "--noise-model",
                         str(tmp_path / "noise.json"), "--duration-s", "5", "--out", str(tmp_path / "run"))
    assert code in (0, 1) and "error" not in err
    assert "frames tracked; latency median 100 ms (95 % 100 ms), processing n/a;" in out


@pytest.mark.parametrize("field, value", [("theta_sigma_rad", "x"), ("theta_sigma_rad", -1.0), ("latency_s", None),
                                          ("valid_fraction", 2.0), ("frames", 0)])
def test_a_noise_model_out_of_range_is_refused_naming_the_field(capsys, tmp_path, field, value):
    # before: TypeError or scipy's "zero norm quaternions" inside the loop (exit 3)
    model = {"theta_bias_rad": 0.0, "theta_sigma_rad": 1e-3, "rate_sigma_rad_s": 1e-3, "rate_delay_s": 0.1,
             "latency_s": 0.1, "valid_fraction": 1.0, "frames": 10} | {field: value}
    (tmp_path / "noise.json").write_text(json.dumps(model))
    code, _, err = run(capsys, "adcs-demo", "--feedback", "tracker-model", "--noise-model",
                       str(tmp_path / "noise.json"), "--duration-s", "5", "--out", str(tmp_path / "run"))
    assert code == 2 and f"startrack adcs-demo: error: noise model {field} must be" in err
