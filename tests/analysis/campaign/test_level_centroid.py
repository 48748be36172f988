"""Level "centroid" on known cases, the truth matching it shares, and its spec (Huffman 2006
Table 4.2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis.campaign._params import SpecError
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign.levels import get_level
from startrack.analysis.campaign.levels._measure import match_truth
from startrack.simulate import get_sensor_preset
from startrack.simulate._radiometry import electrons_from_magnitude

LEVEL = get_level("centroid")
NOISE_OFF = {f"noise_{k}": False for k in ("shot", "dark", "read", "bias", "quantize")}


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **changes}


def test_match_truth_pairs_nearest_first_and_uses_each_detection_once():
    x_true, y_true = np.array([0.0, 1.0, 10.0, 50.0]), np.zeros(4)
    x, y = np.array([0.9, 10.5, 30.0]), np.zeros(3)
    # the detection at 0.9 is nearer the star at 1.0: the star at 0.0 gets nothing
    assert match_truth(x_true, y_true, x, y, 2.0).tolist() == [-1, 0, 1, -1]
    assert match_truth(x_true, y_true, x[:0], y[:0], 2.0).tolist() == [-1] * 4


def test_noise_free_stars_are_all_found_and_centred():
    p = params(mag_v=3.0, sensor="far-mst-seed-eq34", psf_sigma_px=2.5, bit_depth=16, **NOISE_OFF)
    row = LEVEL.run(p, Rotation.identity(), np.random.default_rng(4), 5.0).row
    assert row["status"] == "OK" and row["correct"]
    assert row["n_stars"] == row["n_matched"] == 30
    assert row["centroid_rms_axis_px"] < 0.05  # px: the weighted sum's pixel-phase bias, no noise


def test_the_aperture_sets_the_signal_as_the_radiometry_says():
    base = get_sensor_preset("far-mst-seed-eq34")
    expected = electrons_from_magnitude(
        2.0, aperture_area_m2=3.14e-4, exposure_s=base.exposure_s, transmission=base.optics.transmission,
        quantum_efficiency=base.detector.quantum_efficiency,
        zero_point_photons_s_m2=base.optics.zero_point_photons_s_m2)
    row = LEVEL.run(params(mag_v=2.0, sensor="far-mst-seed-eq34", aperture_area_m2=3.14e-4, stars_per_image=2),
                    Rotation.identity(), np.random.default_rng(0), 5.0).row
    assert row["electrons_per_star"] == pytest.approx(float(expected), rel=1e-12)


def test_noise_spreads_the_centroids_as_the_signal_falls():
    p = params(sensor="far-mst-seed-eq34", aperture_area_m2=3.14e-4, psf_sigma_px=2.5, read_noise_e=40.0,
               dark_current_e_s=410.0, bit_depth=16)
    rms = [LEVEL.run({**p, "mag_v": m}, Rotation.identity(), np.random.default_rng(1), 5.0).row["centroid_rms_axis_px"]
           for m in (1.0, 5.0)]
    assert rms[0] < rms[1] / 4  # 4 magnitudes: 40 times the flux, about sqrt(40) = 6.3 in error


def test_more_stars_than_grid_cells_is_refused():
    with pytest.raises(SpecError, match="stars_per_image"):
        parse_spec('[campaign]\nname = "x"\nlevel = "centroid"\n[base]\nstars_per_image = 31\n')


SEED_42 = {1.0: (5.74, 81.07), 2.0: (5.10, 77.57), 3.0: (2.81, 74.56), 4.0: (1.61, 67.60), 5.0: (0.73, 46.78)}


def test_table42_spec_holds_the_seed_times():
    spec = shipped("huffman2006-table4.2-ws-vs-mle")
    assert spec.sweep == {"mag_v": tuple(SEED_42), "detect_centroid": ("weighted", "mle")}
    assert spec.base["aperture_area_m2"] == 3.14e-4 and spec.base["stars_per_image"] == 30
    seeds = seed_numbers(spec, "Huffman 2006 Table 4.2")
    assert {(dict(k)["mag_v"], dict(k)["detect_centroid"]): v for k, v in seeds.items()} == {
        (m, c): SEED_42[m][i] for m in SEED_42 for i, c in enumerate(("weighted", "mle"))}


def test_table42_tiny_run_gives_every_reference_a_number(tmp_path):
    trials, tables = tiny_run("huffman2006-table4.2-ws-vs-mle", tmp_path,
                              base={"width": 640, "height": 512, "stars_per_image": 6})  # small, to stay quick
    assert tables and all(finite(rows) for rows in tables.values())
    assert not any(math.isnan(v) for v in trials["centroid_rms_axis_px"].to_pylist())
