"""Level "streak" on known cases, the streak scenes it draws, and its spec (Sease 2013 Table 3.1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis._streak_scenes import paths_apart, spin_rate, star_paths
from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign.levels import get_level
from startrack.analysis.campaign.levels._streak import draw_frame
from startrack.analysis.campaign.levels._streaks import in_time_order
from startrack.camera import Camera
from startrack.rate._endpoints import DETECTORS

LEVEL = get_level("streak")
SMALL = {"width": 512, "height": 512, "fov_deg": 11.4, "calibration_frames": 1}
"""The Sease 2013 camera's 80 arcsec/px on a quarter of its pixels: fast frames for the tests."""
SPEC = "sease2013-table3.1-streak-endpoints"
TABLE_3_1 = {  # the notes' Table 3.1: detector -> (endpoint px 10 %, 50 %; rate % 10 %, 50 %)
    "harris": (0.10, 0.10, 0.69, 0.07), "min_eigenvalue": (0.19, 0.20, 1.20, 0.19),
    "trajkovic4": (0.39, 0.37, 2.44, 0.38), "trajkovic8": (0.55, 0.29, 3.49, 0.47),
}


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **SMALL, **changes}


def test_spin_rate_puts_the_axis_theta_from_the_boresight():
    omega = spin_rate(math.radians(30.0), 0.05, math.radians(90.0))
    assert np.linalg.norm(omega) == pytest.approx(0.05, rel=1e-12)
    assert np.degrees(np.arccos(omega[2] / 0.05)) == pytest.approx(30.0, abs=1e-9)
    assert omega[0] == pytest.approx(0.0, abs=1e-15) and omega[1] > 0


def test_a_frame_has_the_exposure_of_its_streak_fraction_and_its_paths_apart():
    p = params(streak_fraction=0.2, stars=6)
    row = LEVEL.run(p, Rotation.identity(), np.random.default_rng(3), 5.0).row
    assert row["exposure_s"] == pytest.approx(0.2 * math.radians(11.4) / 0.05, rel=1e-12)
    assert 30.0 <= row["theta_deg"] <= 90.0 and row["n_true"] == 6
    truth = draw_frame(p, Rotation.identity(), np.random.default_rng(3), 0.2, 6)  # what run drew
    camera = Camera.from_fov(512, 512, fov_deg=11.4)
    paths = star_paths(camera, truth.omega_rad_s, truth.exposure_s, truth.rot_start.apply(truth.icrs))
    assert paths_apart(paths, 15.0)
    assert np.allclose(paths[:, 0], truth.start_xy, atol=0.05)  # px: the simulator's truth is where we put them


def test_clean_bright_streaks_give_small_endpoint_rate_and_attitude_errors():
    p = params(detector="harris", streak_fraction=0.1, read_noise_e=0.0, sky_e=1.0)
    row = LEVEL.run(p, Rotation.from_euler("xyz", [10.0, 20.0, 30.0], degrees=True), np.random.default_rng(5),
                    5.0).row
    assert row["status"] == "OK" and row["correct"]
    assert row["n_stars"] == 10
    assert row["endpoint_err_px"] < 0.15  # px: bias calibrated, no read noise
    assert row["rate_err_pct"] < 1.0
    # the start attitude from ends 0.15 px off: a few arcsec at 80 arcsec/px
    assert row["err_total_arcsec"] < 40.0


def test_in_time_order_swaps_ends_to_the_truth():
    class Scene:
        start_xy = np.array([[10.0, 10.0], [50.0, 50.0]])
        end_xy = np.array([[20.0, 10.0], [60.0, 50.0]])

    a = np.array([[60.1, 50.0], [10.1, 10.0]])  # streak 0 measured is true star 1, its A end is the end
    b = np.array([[50.1, 50.0], [20.1, 10.0]])
    index, starts, ends = in_time_order(Scene, a, b)
    assert index.tolist() == [1, 0]
    assert np.allclose(starts, [[50.1, 50.0], [10.1, 10.0]]) and np.allclose(ends, [[60.1, 50.0], [20.1, 10.0]])


def test_star_count_auto_is_ten_short_and_four_long():
    from startrack.analysis.campaign.levels._streak import star_count

    assert star_count(params(), 0.1) == 10 and star_count(params(), 0.5) == 4
    assert star_count(params(stars=7), 0.5) == 7


def test_bad_ranges_are_refused_before_work():
    text = """[campaign]
name = "x"
level = "streak"
[base]
theta_range_deg = [60.0, 30.0]
"""
    with pytest.raises(SpecError, match="theta_range_deg"):
        parse_spec(text)
    with pytest.raises(SpecError, match="detector"):
        parse_spec(text.replace("theta_range_deg = [60.0, 30.0]", 'detector = "sobel"'))


def test_the_spec_holds_table_3_1():
    spec = shipped(SPEC)
    assert spec.level == "streak"
    assert {(c.params["detector"], c.params["streak_fraction"]) for c in spec.cells()} == {
        (d, f) for d in DETECTORS for f in (0.1, 0.5)}
    endpoint = seed_numbers(spec, "Sease 2013 Table 3.1: single-endpoint")
    rate = seed_numbers(spec, "Sease 2013 Table 3.1: rate error")
    for detector, (e10, e50, r10, r50) in TABLE_3_1.items():
        for fraction, e, r in ((0.1, e10, r10), (0.5, e50, r50)):
            key = (("detector", detector), ("streak_fraction", fraction))
            assert endpoint[key] == e and rate[key] == r


def test_a_tiny_run_of_the_spec_gives_every_reference(tmp_path):
    trials, tables = tiny_run(SPEC, tmp_path, base=SMALL)
    assert trials.num_rows == 8 and set(trials.column("status").to_pylist()) == {"OK"}
    for title, rows in tables.items():
        assert finite(rows), title
    assert np.all(np.asarray(trials.column("rate_err_pct")) < 10.0)  # % : every detector measured a rate


def test_an_unmeasurable_frame_is_a_too_few_stars_row():
    p = params(stars=2, star_electrons=[50.0, 60.0], bias_px=0.0)  # 50 e- over a streak: below the noise
    row = LEVEL.run(p, Rotation.identity(), np.random.default_rng(0), 5.0).row
    assert row["status"] == "TOO_FEW_STARS" and not row["solved"] and not row["correct"]
    assert math.isnan(row["endpoint_err_px"]) and math.isnan(row["err_total_arcsec"])
    assert row["bias_px"] == 0.0 and row["n_stars"] < 2
