"""Level "smearlimit": the rate against the pixel angle, the smear the simulator renders at it,
and its spec (Samaan 2002 Table 1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis.campaign.levels import get_level
from startrack.frames import random_rotations

LEVEL = get_level("smearlimit")


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **changes}


def test_starnav_rate_is_a_tenth_of_its_pixel_per_exposure_and_the_stars_move_that_far():
    rot = random_rotations(None, np.random.default_rng(8))
    row = LEVEL.run(params(exposure_s=0.02), rot, np.random.default_rng(9), 5.0).row
    pixel_rad = 15.84e-6 / 58e-3  # StarNav I: 15.84 um pitch, f = 58 mm
    assert row["max_rate_deg_s"] == pytest.approx(math.degrees(0.1 * pixel_rad / 0.02), rel=1e-12)
    assert row["smear_px"] == pytest.approx(0.1, rel=0.01)  # px; off-axis stars move up to 1 % more
    assert row["smear_px"] <= row["smear_max_px"] <= 0.1 * 1.011
    assert row["correct"] and row["status"] == "OK" and row["n_stars"] > 0


def test_a_wide_field_smears_its_corners_beyond_the_margin():
    row = LEVEL.run(params(camera="", fov_deg=60.0, width=512, height=512, max_mag=5.0),
                    random_rotations(None, np.random.default_rng(1)), np.random.default_rng(2), 5.0).row
    assert row["smear_max_px"] > 0.1 * 1.02 and not row["correct"]  # 1/cos^2 reaches 1.5 at a 60 deg corner


SEED_1 = {0.01: 0.156, 0.02: 0.078, 0.03: 0.052, 0.05: 0.0313}


def test_table1_spec_holds_the_seed_rates_for_both_fields():
    spec = shipped("samaan2002-table1-smear-rate")
    assert spec.sweep == {"camera": ("starnav-i", ""), "exposure_s": tuple(SEED_1)}
    assert (spec.base["fov_deg"], spec.base["width"], spec.base["height"]) == (7.0, 512, 512)
    for title, camera in (("Samaan 2002 Table 1: largest rate", "starnav-i"),
                          ("Samaan 2002 Table 1 beside a 7 deg", "")):
        got = {dict(w)["exposure_s"]: v for w, v in seed_numbers(spec, title).items() if dict(w)["camera"] == camera}
        assert got == SEED_1


def test_table1_tiny_run_reproduces_the_printed_digits(tmp_path):
    _, tables = tiny_run("samaan2002-table1-smear-rate", tmp_path)
    assert all(finite(rows) for rows in tables.values())
    for r in tables["Samaan 2002 Table 1: largest rate for 1/10 px of smear, StarNav I (8 deg field, as the table "
                    "implies)"]:
        digits = len(r["seed"].split(".")[1])
        assert round(r["ours"], digits) == pytest.approx(r["seed_value"], abs=0.6 * 10.0**-digits)
