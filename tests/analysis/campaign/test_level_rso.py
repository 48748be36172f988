"""Level "rso" on known cases, the Table 4.3 opportunities it renders, and its specs (Sease 2013
Tables 4.1-4.4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from astropy.time import Time, TimeDelta
from scipy.spatial.transform import Rotation
from seed_tables_checks import finite, shipped, tiny_run

from startrack.analysis._rso_passes import SEASE2013_CAMERA_ELEMENTS, SEASE2013_RSO_ELEMENTS, camera_rotation, elements
from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign.levels import get_level
from startrack.analysis.campaign.levels._rso import draw_frame, passes, rate_columns, rso_streak
from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.rate._estimate import RateEstimate
from startrack.results import Status
from startrack.simulate import Orbit, in_earth_shadow, sun_moon_km
from startrack.units import DEG

LEVEL = get_level("rso")
SMALL = {"width": 512, "height": 512, "fov_deg": 11.4}
"""The Sease 2013 camera's 80 arcsec/px on a quarter of its pixels: fast frames for the tests."""
CAMERA = Camera.from_fov(1024, 1024, fov_deg=22.8)
SPEC_41_42 = "sease2013-tables4.1-4.2-catalog-free-rate"
SPEC_44 = "sease2013-tables4.3-4.4-rso-detection"


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **changes}


def test_rate_columns_of_a_known_estimate():
    omega = np.array([0.0, 0.05, 0.0])
    est = RateEstimate(Status.OK, omega_rad_s=np.array([0.0, 0.0505, 0.0]))
    cols = rate_columns(est, omega, 0.5)
    assert cols["rate_mag_err_pct"] == pytest.approx(1.0, rel=1e-9)
    assert cols["rate_err_pct"] == pytest.approx(1.0, rel=1e-9) and cols["axis_err_deg"] == pytest.approx(0.0)
    assert cols["displacement_rad"] == pytest.approx(0.02525) and cols["rate_est_deg_s"] == pytest.approx(0.0505 / DEG)
    tilted = RateEstimate(Status.OK, omega_rad_s=0.05 * np.array([math.sin(DEG), math.cos(DEG), 0.0]))
    assert rate_columns(tilted, omega, 0.5)["axis_err_deg"] == pytest.approx(1.0, rel=1e-9)
    assert all(math.isnan(v) for v in rate_columns(RateEstimate(Status.DEGENERATE), omega, 0.5).values())


def test_the_rso_streak_is_found_either_way_round_within_3_px():
    class Scene:
        is_rso = np.array([False, True])
        start_xy = np.array([[0.0, 0.0], [100.0, 100.0]])
        end_xy = np.array([[10.0, 0.0], [150.0, 110.0]])

    a = np.array([[0.1, 0.0], [151.0, 111.0]])
    b = np.array([[10.1, 0.0], [101.0, 101.0]])
    assert rso_streak(Scene, a, b) == 1
    assert rso_streak(Scene, a + [5.0, 0.0], b) is None


def test_a_slewing_frame_with_an_rso_flags_it_and_no_star():
    p = params(**SMALL, rate_rad_s=0.05, rso=True, rso_mag=3.0, stars=8, detector="harris", bias_px=0.64,
               rso_own_range=(0.4, 0.6))
    row = LEVEL.run(p, Rotation.from_euler("z", 40.0, degrees=True), np.random.default_rng(11), 5.0).row
    assert row["rso_present"] and row["rso_measured"]
    assert row["found_combined"] and row["found_centre_of_rotation"]
    assert row["false_combined"] == 0 and row["false_centre_of_rotation"] == 0
    assert row["rso_own_motion_px"] > 5.0  # px: 0.4-0.6 of a 0.025 rad turn at 80 arcsec/px is 26-39 px
    assert row["n_star_streaks"] == 8


def test_without_an_rso_the_catalog_free_rate_is_close_and_nothing_is_found():
    p = params(**SMALL, rate_rad_s=2.0 * DEG, rso=False, stars=10)
    row = LEVEL.run(p, Rotation.identity(), np.random.default_rng(2), 5.0).row
    assert row["status"] == "OK" and row["correct"] and not row["rso_present"]
    assert row["rate_err_pct"] < 1.0 and row["axis_err_deg"] < 0.5
    assert row["displacement_deg"] == pytest.approx(1.0, rel=0.01)  # 2 deg/s for 0.5 s
    assert not any(row[f"found_{k}"] for k in ("centre_of_rotation", "angular_displacement", "combined"))


def test_each_opportunity_sees_the_rso_lit_inside_the_image_with_no_earth_or_sun():
    """Against the orbits propagated directly (not through the scene's snapshots)."""
    p = params(scenario="orbits")
    found = passes(p)
    assert len(found) >= 4
    epoch = Time(p["epoch_utc"], scale="utc")
    t = np.unique(np.concatenate([c.start_s + np.array([0.0, 0.25, 0.5]) for c in found]))
    obs = Orbit.from_elements(epoch, elements(SEASE2013_CAMERA_ELEMENTS, "c")).states(t)[0]
    rso = Orbit.from_elements(epoch, elements(SEASE2013_RSO_ELEMENTS, "r")).states(t)[0]
    rots = camera_rotation((0.0, 0.05, 0.0), t)
    x, y = CAMERA.vector_to_pixel(rots.apply(rso - obs))
    assert np.all(CAMERA.in_image(x, y, 29.0))  # px: 30 asked, the light time moves it < 1 px
    sun = sun_moon_km(epoch + TimeDelta(found[0].start_s, format="sec"))[0][0]
    assert not np.any(in_earth_shadow(rso, sun))
    bore, nadir = rots.inv().apply([0.0, 0.0, 1.0]), -obs
    angle = np.arctan2(np.linalg.norm(np.cross(bore, nadir), axis=1), np.sum(bore * nadir, axis=1))
    earth_edge = angle - np.arcsin(6378.137 / np.linalg.norm(nadir, axis=1))
    assert np.all(earth_edge > math.radians(CAMERA.fov_diagonal_deg) / 2)
    assert np.all(np.diff([c.start_s for c in found]) > 0)


def test_an_orbit_frame_renders_the_rso_where_the_orbits_put_it():
    p = params(scenario="orbits", opportunity=0, stars=6, detector="harris", bias_px=0.64)
    out = LEVEL.run(p, Rotation.identity(), np.random.default_rng(1), 5.0)
    scene, chosen = draw_frame(p, Rotation.identity(), np.random.default_rng(1))  # what run drew
    assert chosen is passes(p)[0] and scene.is_rso[-1] and out.row["opportunities"] == len(passes(p))
    assert scene.rot_start.approx_equal(chosen.rot_start, atol=1e-9)
    assert out.truth.rsos.rendered[0] and out.truth.rsos.x_start[0] == scene.start_xy[-1, 0]
    assert out.row["start_s"] == chosen.start_s and out.row["rso_range_km"] == pytest.approx(chosen.range_km)
    assert out.row["rso_measured"]


def test_a_missing_opportunity_and_a_bad_epoch_are_refused():
    text = """[campaign]
name = "x"
level = "rso"
[base]
scenario = "orbits"
opportunity = 500
"""
    with pytest.raises(SpecError, match="opportunity: the orbit scenario has"):
        parse_spec(text)
    with pytest.raises(SpecError, match="orbit scenario"):
        parse_spec(text.replace("opportunity = 500", 'epoch_utc = "yesterday"'))
    with pytest.raises(SpecError, match="axis"):
        parse_spec(text.replace('scenario = "orbits"\nopportunity = 500', "axis = [0.0, 0.0, 0.0]"))


def test_the_specs_hold_tables_4_1_to_4_4():
    spec = shipped(SPEC_41_42)
    rows = {r["label"]: r["seed"] for ref in spec.reference if ref["title"].startswith("Sease 2013 Table 4.")
            for r in ref["rows"]}
    assert rows["rate (deg/s)"] == 1.986 and rows["rate (rad/s)"] == 0.0497
    assert rows["displacement (deg)"] == 0.993 and rows["displacement (rad)"] == 0.0248
    assert len(spec.cells()) == 8
    spec = shipped(SPEC_44)
    assert spec.base["camera_elements"] == SEASE2013_CAMERA_ELEMENTS
    assert spec.base["rso_elements"] == SEASE2013_RSO_ELEMENTS and spec.base["rso_mag"] == 4.0
    assert spec.sweep["opportunity"] == tuple(range(len(passes(spec.cells()[0].params))))
    correct = next(r for r in spec.reference if "(Correct)" in r["title"])
    false = next(r for r in spec.reference if "(False)" in r["title"])
    assert [r["seed"] for r in correct["rows"][:3]] == [12, 10, 12]
    assert [r["seed"] for r in false["rows"][:3]] == [3, 0, 0]


def test_tiny_runs_of_the_specs_give_every_reference(tmp_path):
    tiny = {"width": 384, "height": 384, "fov_deg": 8.55, "stars": 5}  # 80 arcsec/px
    trials, tables = tiny_run(SPEC_41_42, tmp_path / "a", base=tiny)
    assert trials.num_rows == 8
    rates = [r for title, rows in tables.items() if "Table 4.1 (" in title for r in rows]
    assert finite(rates)
    trials, tables = tiny_run(SPEC_44, tmp_path / "b", base={"stars": 5}, sweep={"opportunity": [2]})
    assert trials.num_rows == 2 and set(trials.column("detector").to_pylist()) == {"segment", "harris"}
    counts = [r for title, rows in tables.items() if "Table 4.4" in title for r in rows]
    assert len(counts) == 12 and finite(counts)


def test_orbital_elements_are_checked_by_name():
    with pytest.raises(InvalidInputError, match="rso_elements: perigee"):
        elements((6000.0, 0.0, 0.0, 0.0, 0.0, 0.0), "rso_elements")
    with pytest.raises(InvalidInputError, match="camera_elements: six elements"):
        elements((7000.0, 0.0), "camera_elements")
