"""Level "prefilter": the candidate mask against the normal distribution, a frame's counts, the
fixed pointing, and its spec (Huffman 2006 Table 7.2)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign.levels import get_level
from startrack.analysis.campaign.levels._prefilter import candidate_mask, trial_pointing
from startrack.detect import StarDetector
from startrack.frames import angle_between, boresight, random_rotations, rotation_from_radec_roll

LEVEL = get_level("prefilter")


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **changes}


@pytest.mark.parametrize("k", [1.0, 2.0])
def test_candidates_of_pure_noise_are_the_normal_tail_above_k_sigma(k):
    """The share of pure-noise pixels above the mask's level is the normal tail at k sigma, to
    0.1 sigma (the detector estimates the noise robustly, from the upper half)."""
    image = np.random.default_rng(5).normal(1000.0, 20.0, (512, 512))
    share = float(np.mean(candidate_mask(StarDetector(threshold="prefilter-window", pixel_sigma=k), image)))
    assert norm.isf(share) == pytest.approx(k, abs=0.1)  # sigma


def test_a_frame_counts_its_detections_and_the_true_stars_found():
    p = params(camera="far-mst", sensor="far-mst", max_mag=6.0, detect_threshold="prefilter-grid",
               detect_pixel_sigma=3.0, detect_centroid="weighted", pointing_radec_roll_deg=(83.0, 5.0, 20.0))
    row = LEVEL.run(p, random_rotations(None, np.random.default_rng(0)), np.random.default_rng(1), 5.0).row
    assert 0 < row["n_matched"] <= row["n_truth"] and row["n_matched"] <= row["n_stars"]
    assert row["correct"] == (row["n_stars"] == row["n_matched"]) and row["status"] == "OK"
    assert row["n_candidates"] > 0 and row["time_prefilter_s"] > 0.0
    assert row["dec_deg"] == pytest.approx(5.0, abs=1e-9)  # the fixed pointing, no spread


def test_a_fixed_pointing_is_turned_about_camera_y_within_the_spread():
    p = params(pointing_radec_roll_deg=(83.0, 5.0, 20.0), pointing_spread_deg=1.3)
    start = rotation_from_radec_roll(*np.radians((83.0, 5.0, 20.0)))
    for seed in range(20):
        rot = trial_pointing(p, None, np.random.default_rng(seed))
        turn = start * rot.inv()
        assert np.degrees(angle_between(boresight(rot), boresight(start))) <= 1.3 + 1e-9
        assert np.allclose(turn.as_rotvec()[[0, 2]], 0.0, atol=1e-12)  # about camera y only
    free = random_rotations(None, np.random.default_rng(9))
    assert trial_pointing(params(), free, np.random.default_rng(0)) is free


def test_a_threshold_without_prefilter_is_refused():
    with pytest.raises(SpecError, match="detect_threshold"):
        parse_spec('[campaign]\nname = "x"\nlevel = "prefilter"\n[base]\ndetect_threshold = "ksigma"\n')


SEED_72 = {1.0: ((10, 17, 1.1860), (8, 15, 0.3339)), 1.5: ((8, 15, 0.4976), (4, 11, 0.3215)),
           2.0: ((5, 10, 0.1698), (3, 8, 0.3216)), 3.0: ((3, 8, 0.0132), (2, 5, 0.3192)),
           4.0: ((2, 6, 0.0023), (1, 3, 0.3180))}


def test_table72_spec_holds_the_seed_ranges_and_times():
    spec = shipped("huffman2006-table7.2-prefilter-speed")
    assert spec.trials == 14 and spec.sweep["detect_pixel_sigma"] == tuple(SEED_72)
    for title, i in (("Huffman 2006 Table 7.2: pre-filter time", 2),
                     ("Huffman 2006 Table 7.2: stars centroided, fewest", 0),
                     ("Huffman 2006 Table 7.2: stars centroided, most", 1)):
        got = {(dict(w)["detect_pixel_sigma"], dict(w)["detect_threshold"]): v
               for w, v in seed_numbers(spec, title).items()}
        assert got == {(k, f"prefilter-{form}"): SEED_72[k][j][i] for k in SEED_72
                       for j, form in enumerate(("window", "grid"))}


def test_table72_tiny_run_gives_every_reference_a_number(tmp_path):
    """On a small pinhole frame of the same field and scale, to stay quick."""
    _, tables = tiny_run("huffman2006-table7.2-prefilter-speed", tmp_path,
                         base={"camera": "", "width": 320, "height": 256, "fov_deg": 7.5})
    assert len(tables) == 3 and all(finite(rows) for rows in tables.values())
