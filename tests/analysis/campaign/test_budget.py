"""Error budgets: the cells a [budget] table asks for, the refusals (naming the key), the ECSS
decomposition against a hand computation, and the image level's shared attitudes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from startrack.analysis.campaign._budget import BUDGET_KEYS, SOURCES, budget_manifest
from startrack.analysis.campaign._budget_terms import contribution, ecss_terms, variance_components
from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign._trials import trial_rng
from startrack.analysis.campaign.levels._image import PARAMS, field_and_dither, trial_attitude, trial_key
from startrack.camera import Camera
from startrack.frames import angle_between, boresight

SPEC = """
[campaign]
name = "budget-test"
level = "image"
mode = "budget"
trials = 12
seed = 3
[base]
width = 256
height = 256
fov_deg = 8.0
psf_sigma_px = 1.6
rate_deg_s = [0.2, 0.0, 0.0]
[budget]
repeats = 3
dithers = 2
timing_error_s = 0.05
"""

SWITCHES = {"shot_noise": {"noise_shot"}, "read_noise": {"noise_read"},
            "dark_current": {"noise_dark", "noise_dsnu", "noise_hot_pixels", "noise_read", "read_noise_e"},
            "psf_width": {"psf_sigma_px"}, "quantisation": {"noise_quantize", "noise_saturate"},
            "distortion": {"distortion_known"},
            "proper_motion": {"solver_epoch_jyear"}, "aberration": {"aberration_annual"},
            "timing": {"timing_error_s"}}
"""The parameters each source alone changes from the baseline (the dark current without shot
noise also brings a read noise of its Poisson variance)."""


def _with(text: str, old: str, new: str) -> str:
    assert old in text
    return text.replace(old, new)


def test_cells_are_the_baseline_all_on_then_each_source_alone():
    spec = parse_spec(SPEC)
    cells = spec.cells()
    assert [c.source for c in cells] == ["baseline", "all", *SOURCES]
    assert [c.label for c in cells] == [c.source for c in cells]
    base, every = cells[0].params, cells[1].params
    assert not any(base[k] for k in ("noise_shot", "noise_read", "noise_dark", "noise_quantize", "noise_saturate",
                                     "aberration_annual"))
    assert base["psf_sigma_px"] == 0.8 and base["distortion_known"] and base["solver_epoch_jyear"] is None
    assert base["timing_error_s"] == 0.0 and base["aberration_velocity_km_s"] == (0.0, 0.0, 0.0)
    assert all(every[k] for k in ("noise_shot", "noise_read", "noise_dark", "noise_quantize", "aberration_annual"))
    assert every["psf_sigma_px"] == 1.6 and not every["distortion_known"] and every["solver_epoch_jyear"] == 1991.25
    assert every["timing_error_s"] == 0.05 and every["read_noise_e"] is None  # the sensor's own read noise
    for cell in cells:
        assert cell.params["calibrated"] and cell.params["k1"] == 0.01  # a lens in every cell (the pinhole's default)
        assert (cell.params["frames_per_attitude"], cell.params["attitudes_per_field"]) == (3, 2)
    for cell in cells[2:]:
        changed = {k for k in base if cell.params[k] != base[k]}
        assert changed == SWITCHES[cell.source], cell.source
    dark = cells[2 + list(SOURCES).index("dark_current")].params
    assert dark["read_noise_e"] == pytest.approx(math.sqrt(20.0 * 0.2))  # generic-cmos: 20 e-/s for 0.2 s


def test_sources_and_cases_choose_the_cells_and_the_manifest_indexes_them():
    text = _with(SPEC, "timing_error_s = 0.05", 'sources = ["timing", "shot_noise"]\n'
                 '[[budget.case]]\nname = "wide"\nfov_deg = 20.0\n[[budget.case]]\nname = "narrow"\nfov_deg = 5.0')
    spec = parse_spec(text)
    cells = spec.cells()
    assert [c.label for c in cells] == ["wide: baseline", "wide: all", "wide: timing", "wide: shot_noise",
                                        "narrow: baseline", "narrow: all", "narrow: timing", "narrow: shot_noise"]
    assert [c.params["fov_deg"] for c in cells] == [20.0] * 4 + [5.0] * 4
    assert cells[5].params["noise_shot"] and cells[5].params["timing_error_s"] == 0.01
    assert not cells[6].params["noise_shot"]
    manifest = budget_manifest(spec, cells)
    assert manifest["sources"] == ["timing", "shot_noise"] and (manifest["baseline"], manifest["all"]) == (0, 1)
    assert manifest["fields"] == 2 and (manifest["repeats"], manifest["dithers"]) == (3, 2)
    narrow = manifest["cases"][1]
    assert (narrow["name"], narrow["baseline"], narrow["all"], narrow["sources"]) == \
        ("narrow", 4, 5, {"timing": 6, "shot_noise": 7})
    assert narrow["on"]["timing"] == "time tag off by 0.01 s at [0.2, 0, 0] deg/s"
    assert narrow["off"]["timing"] == "exact time tag"


@pytest.mark.parametrize(("old", "new", "words"), [
    ("repeats = 3", "repeat = 3", "[budget] repeat: unknown key; valid: sources, repeats"),
    ("repeats = 3", 'sources = ["timing", "seeing"]', "[budget] sources: unknown source 'seeing'; valid: shot_noise"),
    ("repeats = 3", 'sources = "timing"', "[budget] sources: must be a non-empty list"),
    ("repeats = 3", "repeats = 0", "[budget] repeats:"),
    ("timing_error_s = 0.05", 'timing_error_s = "late"', "[budget] timing_error_s:"),
    ("psf_sigma_px = 1.6", "noise_shot = false", "[base] noise_shot: set by the budget in every cell"),
    ("psf_sigma_px = 1.6", "calibrated = false", "[base] calibrated: set by the budget"),
    ("trials = 12", "trials = 10", "trials = 10 must be whole star fields: a multiple of [budget] repeats x dithers"),
    ("[budget]", "[sweep]\nfov_deg = [5.0, 10.0]\n[budget]", "[sweep] is not read in budget mode"),
    ("timing_error_s = 0.05", "[[budget.case]]\nname = \"a\"\nfov_dg = 3.0",
     "[[budget.case]] a fov_dg: unknown parameter of this level"),
    ("timing_error_s = 0.05", "[[budget.case]]\nfov_deg = 3.0", "[[budget.case]] 0: needs a name"),
    ("timing_error_s = 0.05", "[[budget.case]]\nname = \"a\"\ntiming_error_s = 1.0",
     "[[budget.case]] a timing_error_s: set by"),
])
def test_bad_budget_tables_are_refused_naming_the_key(old, new, words):
    with pytest.raises(SpecError, match=None) as info:
        parse_spec(_with(SPEC, old, new))
    assert words in str(info.value)


def test_a_budget_on_another_level_is_refused():
    text = '[campaign]\nname = "b"\nlevel = "stars"\nmode = "budget"\ntrials = 6\n'
    with pytest.raises(SpecError, match='mode = "budget" runs on level "image", not \'stars\''):
        parse_spec(text)


def test_every_budget_key_is_documented():
    assert all(p.doc for p in BUDGET_KEYS.values()) and all(s.doc for s in SOURCES.values())


def _nested(fields: int, dithers: int, repeats: int) -> tuple[np.ndarray, np.ndarray]:
    k = np.arange(fields * dithers * repeats)
    return k // (dithers * repeats), (k // repeats) % dithers


def test_variance_components_match_a_hand_computed_nested_anova():
    # 3 fields x 2 dithers x 2 repeats, errors chosen by hand
    e = np.array([1.0, 3.0, 2.0, 2.0, 6.0, 4.0, 9.0, 7.0, -2.0, 0.0, -1.0, -5.0])
    field, dither = _nested(3, 2, 2)
    # attitude means: 2, 2 | 5, 8 | -1, -3; field means 2, 6.5, -2; grand mean 2.1666..
    ms_within = ((1 + 1) + (0 + 0) + (1 + 1) + (1 + 1) + (1 + 1) + (4 + 4)) / 6          # 18 / 6 = 3
    ms_dither = 2 * ((0 + 0) + (2.25 + 2.25) + (1 + 1)) / 3                                 # 13 / 3
    grand = np.mean([2.0, 6.5, -2.0])
    ms_field = 4 * np.sum((np.array([2.0, 6.5, -2.0]) - grand) ** 2) / 2
    fov, pixel, temporal = variance_components(e, field, dither)
    assert temporal == pytest.approx(ms_within)
    assert pixel == pytest.approx((ms_dither - ms_within) / 2)
    assert fov == pytest.approx((ms_field - ms_dither) / 4)


def test_ecss_terms_recover_known_components_of_a_synthetic_trial_table():
    rng = np.random.default_rng(11)
    fields, dithers, repeats = 400, 3, 4
    field, dither = _nested(fields, dithers, repeats)
    sigma = {"fov": np.array([2.0, 1.0, 10.0]), "pixel": np.array([0.5, 0.8, 3.0]),
             "temporal": np.array([1.5, 1.5, 6.0])}
    bias = np.array([0.7, -0.4, 5.0])
    err = (bias + sigma["fov"] * rng.standard_normal((fields, 3))[field]
           + sigma["pixel"] * rng.standard_normal((fields * dithers, 3))[field * dithers + dither]
           + sigma["temporal"] * rng.standard_normal((len(field), 3)))
    terms = ecss_terms(err, field, dither)
    assert terms.n == len(field)
    assert np.all(np.abs(terms.bias - bias) <= 4 * sigma["fov"] / math.sqrt(fields))
    np.testing.assert_allclose(np.sqrt(terms.temporal), sigma["temporal"], rtol=0.04)
    np.testing.assert_allclose(np.sqrt(terms.pixel_spatial), sigma["pixel"], rtol=0.15)
    np.testing.assert_allclose(np.sqrt(terms.fov_spatial), sigma["fov"], rtol=0.12)
    assert terms.size("temporal", "cross") == pytest.approx(math.sqrt(terms.temporal[0] + terms.temporal[1]))
    assert terms.size("bias", "roll") == pytest.approx(abs(terms.bias[2]))
    parts = sum(terms.power(t, "roll") for t in ("bias", "fov_spatial", "pixel_spatial", "temporal"))
    assert parts == pytest.approx(terms.power("total", "roll"), rel=0.02)  # the terms add up to the mean square


def test_contributions_are_root_sum_square_differences_and_bias_shifts():
    field, dither = _nested(2, 2, 2)
    noise = np.array([[1.0, -1.0, 2.0], [-1.0, 1.0, -2.0]] * 4)
    base = ecss_terms(noise, field, dither)
    shifted = ecss_terms(noise + [3.0, 4.0, -1.0], field, dither)        # a constant error: bias only
    assert contribution(shifted, base, "bias", "cross") == pytest.approx(5.0)
    assert contribution(shifted, base, "bias", "roll") == pytest.approx(1.0)
    assert contribution(shifted, base, "temporal", "cross") == pytest.approx(0.0, abs=1e-12)
    louder = ecss_terms(noise * 2.0, field, dither)                       # temporal variance x 4
    expected = math.sqrt(louder.power("temporal", "cross") - base.power("temporal", "cross"))
    assert contribution(louder, base, "temporal", "cross") == pytest.approx(expected)
    assert contribution(base, louder, "temporal", "cross") == pytest.approx(-expected)


def test_with_one_repeat_the_temporal_noise_is_not_separable():
    field, dither = _nested(4, 2, 1)
    fov, pixel, temporal = variance_components(np.arange(8.0), field, dither)
    assert math.isnan(temporal) and math.isfinite(pixel) and math.isfinite(fov)


def _params(**changes):
    return {**{name: p.default for name, p in PARAMS.items()}, **changes}


def test_shared_attitudes_follow_fields_and_dithers_and_ignore_the_cell():
    camera = Camera.from_fov(256, 256, 8.0)
    params = _params(frames_per_attitude=2, attitudes_per_field=3, dither_px=1.0)
    assert [field_and_dither(k, params) for k in range(7)] == [(0, 0), (0, 0), (0, 1), (0, 1), (0, 2), (0, 2), (1, 0)]
    own = trial_attitude(_params(), "engine", trial_rng(5, 0, 0), camera)
    assert own == "engine"  # frames_per_attitude = 0: the campaign's attitude
    rot = {(c, k): trial_attitude(params, None, trial_rng(5, c, k), camera) for c in (0, 4) for k in range(7)}
    for k in range(7):
        assert np.allclose(rot[0, k].as_quat(), rot[4, k].as_quat())  # every cell sees the same skies
    assert np.allclose(rot[0, 0].as_quat(), rot[0, 1].as_quat())     # repeated frames of one attitude
    step = angle_between(boresight(rot[0, 0]), boresight(rot[0, 2]))
    assert 0.0 < step <= math.sqrt(2.0) / camera.fx                   # dithers: within a pixel on each axis
    far = angle_between(boresight(rot[0, 0]), boresight(rot[0, 6]))
    assert far > 0.01                                                 # another field
    assert trial_key(np.random.default_rng(0)) is None and trial_key(trial_rng(5, 2, 9)) == (5, 2, 9)


@pytest.mark.parametrize(("name", "cases"), [("error-budget", ["base"]),
                                             ("fowler2013-error-budget", ["aptina", "droid"])])
def test_the_shipped_budgets_parse_and_their_references_select_cells(name, cases):
    from startrack.analysis.campaign._reference import match_cells
    from startrack.analysis.campaign._run import _manifest
    from startrack.analysis.campaign._shipped import find_spec
    from startrack.analysis.campaign._spec import load_spec

    spec = load_spec(find_spec(name))
    cells = spec.cells()
    assert len(cells) == len(cases) * (2 + len(SOURCES))
    manifest = _manifest(spec, 10)
    assert [c["name"] for c in manifest["budget"]["cases"]] == cases
    for ref in spec.reference:
        for row in ref["rows"]:
            assert len(match_cells(manifest, row["where"])) == 1, row
