"""Level "photometry": the thresholded weighted sum on known images, and its spec (Huffman 2006
Table 5.3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis.campaign.levels import get_level
from startrack.analysis.campaign.levels._photometry import threshold_adu, weighted_sum_mags
from startrack.frames import random_rotations
from startrack.simulate import get_sensor_preset, magnitude_from_electrons, render_gaussian_psf

LEVEL = get_level("photometry")
SENSOR = get_sensor_preset("far-mst-seed-eq34")


def _image(x, y, electrons):
    """Bias + mean dark + the stars, in ADU, without noise."""
    det = SENSOR.detector
    signal = render_gaussian_psf((200, 300), x, y, electrons, SENSOR.psf_sigma_px)
    return (signal + SENSOR.dark_e) / det.gain_e_per_adu + det.bias_adu


def test_with_no_threshold_the_sum_is_the_whole_star():
    x, y, e = np.array([60.3, 200.8]), np.array([80.4, 120.1]), np.array([5e4, 2e5])
    mags = weighted_sum_mags(_image(x, y, e), x, y, SENSOR, 0.0)
    assert mags == pytest.approx(magnitude_from_electrons(e, SENSOR), abs=1e-3)  # mag: stamp edges only


def test_the_threshold_loses_the_wings_and_two_stars_in_one_cluster_are_not_measured():
    x, y, e = np.array([60.0, 63.0, 200.0]), np.array([80.0, 80.0, 120.0]), np.array([5e4, 5e4, 3e4])
    mags = weighted_sum_mags(_image(x, y, e), x, y, SENSOR, 5.0)
    assert np.isnan(mags[:2]).all()  # 3 px apart: one cluster
    true = float(magnitude_from_electrons(3e4, SENSOR))
    assert true < mags[2] < true + 0.5  # mag: fainter, the wings below the threshold are lost


def test_threshold_is_k_times_dark_and_read_noise_in_adu():
    det = SENSOR.detector
    assert threshold_adu(SENSOR, 5.0) == pytest.approx(5.0 * math.sqrt(SENSOR.dark_e + det.read_noise_e**2)
                                                       / det.gain_e_per_adu)


def test_a_trial_reports_its_first_star_only_when_every_star_was_measured():
    base = {name: p.default for name, p in LEVEL.params.items()}
    base.update(sensor="far-mst-seed-eq34", noise_saturate=False, noise_quantize=False)
    rot = random_rotations(None, np.random.default_rng(2))
    bright = LEVEL.run({**base, "mag_v": 1.0}, rot, np.random.default_rng(3), 5.0).row
    assert bright["status"] == "OK" and bright["n_stars"] == 20 and abs(bright["mag_err_v"]) < 0.05
    faint = LEVEL.run({**base, "mag_v": 9.0}, rot, np.random.default_rng(3), 5.0).row
    assert faint["status"] == "TOO_FEW_STARS" and math.isnan(faint["mag_err_v"]) and not faint["correct"]


SEED_53 = {0.0: (0.0309, 0.0427), 1.0: (0.0311, 0.0324), 2.0: (0.0353, 0.0419), 3.0: (0.0552, 0.0414),
           4.0: (0.1362, 0.0685)}


def test_table53_spec_holds_the_seed_numbers_for_both_signal_scales():
    spec = shipped("huffman2006-table5.3-magnitude-error")
    assert spec.sweep == {"sensor": ("far-mst-seed-eq34", "far-mst"), "mag_v": tuple(SEED_53)}
    assert spec.base["aperture_area_m2"] == pytest.approx(math.pi * 0.01**2, rel=1e-8)
    seed_scale = "far-mst-seed-eq34"
    for title, i, sensor in (("Huffman 2006 Table 5.3: mean magnitude error (measured - true), seed", 0, seed_scale),
                             ("Huffman 2006 Table 5.3: standard deviation of the magnitude error, seed", 1, seed_scale),
                             ("Huffman 2006 Table 5.3: mean magnitude error, physical", 0, "far-mst"),
                             ("Huffman 2006 Table 5.3: standard deviation of the magnitude error, physical", 1,
                              "far-mst")):
        seeds = {dict(k)["mag_v"]: v for k, v in seed_numbers(spec, title).items() if dict(k)["sensor"] == sensor}
        assert seeds == {m: SEED_53[m][i] for m in SEED_53}


def test_table53_tiny_run_gives_the_seed_scale_references_a_number(tmp_path):
    """On small frames (the 512 px StarNav I) with 5 stars, to stay quick; a mean needs one kept
    frame, a standard deviation two."""
    _, tables = tiny_run("huffman2006-table5.3-magnitude-error", tmp_path, trials=3,
                         base={"camera": "starnav-i", "stars_per_image": 5})
    for title, rows in tables.items():
        need = 2 if "standard deviation" in title else 1
        assert [math.isfinite(r["ours"]) for r in rows] == [r["n_used"] >= need for r in rows]
    assert finite(tables["Huffman 2006 Table 5.3: mean magnitude error (measured - true), seed's eq. 3.4 signal "
                         "scale"][1:3])  # V 1-2: bright, all measured in these frames
