"""Level "groupmatch" (Jacobs 1995's matching trade): the attitude region, the star lists, the
judgement of a match, a few trials of each method, and its spec (Tables 3-5 to 3-7)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis.campaign.levels import get_level
from startrack.analysis.campaign.levels._groupmatch import row_values
from startrack.analysis.campaign.levels._sunsat import (
    CAMERA,
    MIN_SEPARATION_PX,
    guides,
    misidentified,
    region_attitudes,
    star_list,
)
from startrack.frames import boresight, vector_to_radec

LEVEL = get_level("groupmatch")


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **changes}


def test_region_boresights_lie_near_the_anti_normal_of_a_97_deg_orbit():
    """The anti-normal of an orbit of inclination 97 deg and node N points at Dec +7 deg, RA N + 90
    deg; roll (+-10 deg) and yaw (+-5 deg) tilt it by at most 11.2 deg."""
    ra, dec = vector_to_radec(np.array([boresight(r) for r in region_attitudes(2000, np.random.default_rng(4))]))
    tilt = math.hypot(10.0, 5.0) + 0.1
    assert np.all(np.abs(np.degrees(dec) - 7.0) <= tilt)
    assert np.all((np.degrees(ra) >= 90.0 - 12.0) & (np.degrees(ra) <= 210.0 + 12.0))


def test_noise_free_lists_are_the_projected_stars_brightest_first_and_resolved():
    g = guides()
    truth = region_attitudes(1, np.random.default_rng(6))[0]
    s = star_list(truth, g, 0.0, 0.0, np.random.default_rng(0))
    assert 3 <= len(s) <= 20 and np.all(np.diff(s.mags) >= 0)
    row_of = {int(h): i for i, h in enumerate(g.hip)}
    rows = [row_of[int(h)] for h in s.hip]
    x, y = CAMERA.vector_to_pixel(truth.apply(g.full.vectors[rows]))
    assert np.allclose(x, s.x, atol=1e-9) and np.allclose(y, s.y, atol=1e-9)  # px
    gaps = np.hypot(s.x[:, None] - s.x[None], s.y[:, None] - s.y[None]) + np.eye(len(s)) * 1e9
    assert gaps.min() >= MIN_SEPARATION_PX


def test_a_misidentification_is_a_star_more_than_a_pixel_angle_away():
    hip = guides().hip
    assert not misidentified(hip[:5], hip[:5])
    assert misidentified(hip[:5], hip[[0, 1, 2, 3, 100]])


def test_a_seed_row_sets_the_noise_and_tolerances_unless_one_is_given():
    assert row_values(params(seed_row=5)) == {"sigma_p_urad": 100.0, "sigma_mv": 0.3, "d_uncert_urad": 200.0,
                                              "mv_uncert": 0.45}
    assert row_values(params(seed_row=1, d_uncert_urad=80.0))["d_uncert_urad"] == 80.0


@pytest.mark.parametrize("method", ["vb-sub", "vb-group", "vb-allsky", "quads"])
def test_no_method_matches_wrongly_and_failures_are_split_by_star_count(method):
    rows = [LEVEL.run(params(match_method=method), None, np.random.default_rng(k), 5.0).row for k in range(6)]
    assert not any(r["wrong"] for r in rows)  # the seed's key result
    assert sum(r["correct"] for r in rows) >= 4
    for r in rows:
        assert r["correct"] == r["solved"] and r["fail_few"] == (not r["solved"] and r["n_stars"] < 3)
        assert r["fail_many"] == (not r["solved"] and r["n_stars"] >= 3)
        assert (method == "vb-group") == math.isnan(r["err_total_arcsec"]) or not r["solved"]


SEED_ROWS = {1: (0.819, 4, 177), 2: (0.978, 5, 17), 3: (0.988, 3, 9), 4: (0.994, 2, 4), 5: (0.972, 4, 24)}


def test_tables_spec_holds_the_seed_rows_as_shares_of_1000():
    spec = shipped("jacobs1995-tables3-5-3-7-matching")
    assert spec.sweep == {"seed_row": (1, 2, 3, 4, 5), "match_method": ("vb-sub", "vb-group", "vb-allsky", "quads")}
    for title, i, scale in (("Jacobs 1995 Tables 3-5 to 3-7: success", 0, 1.0),
                            ("Jacobs 1995 Tables 3-5 to 3-7: failures with fewer", 1, 1e-3),
                            ("Jacobs 1995 Tables 3-5 to 3-7: failures with 3", 2, 1e-3)):
        for where, value in seed_numbers(spec, title).items():
            assert value == pytest.approx(SEED_ROWS[dict(where)["seed_row"]][i] * scale, abs=1e-12)
    assert set(seed_numbers(spec, "Jacobs 1995 Tables 3-5 to 3-7: wrong").values()) == {0.0}


def test_tables_tiny_run_gives_every_reference_a_number(tmp_path):
    _, tables = tiny_run("jacobs1995-tables3-5-3-7-matching", tmp_path)
    assert len(tables) == 6 and all(finite(rows) for rows in tables.values())
