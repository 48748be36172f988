"""Level "smear" on known cases, its two error metrics against direct computations, and its spec
(Samaan 2002 Table 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from seed_tables_checks import finite, seed_numbers, shipped, tiny_run

from startrack.analysis.campaign._rerun import rerun_trial
from startrack.analysis.campaign.levels import get_level
from startrack.analysis.campaign.levels._smear import image_rms_rad, interstar_rms_rad
from startrack.camera import Camera
from startrack.units import DEG

LEVEL = get_level("smear")
SPEC = "samaan2002-table2-smear-centroids"
IFOV_URAD = 1e6 * math.radians(8.0) / 512  # 272.7 urad: StarNav I as Table 1 implies it


def params(**changes):
    return {**{name: p.default for name, p in LEVEL.params.items()}, **changes}


def test_interstar_rms_of_one_star_moved_along_its_pair():
    a, b = np.array([0.0, 0.0, 1.0]), np.array([math.sin(0.01), 0.0, math.cos(0.01)])
    moved = np.array([math.sin(0.01 + 2e-5), 0.0, math.cos(0.01 + 2e-5)])
    # one pair, its angle grown by 20 urad
    assert interstar_rms_rad(np.stack([a, moved]), np.stack([a, b])) == pytest.approx(2e-5, rel=1e-6)
    # three stars, one moved by 20 urad along the line of the other two: two pairs change by 20 urad
    c = np.array([math.sin(0.02), 0.0, math.cos(0.02)])
    rms = interstar_rms_rad(np.stack([a, moved, c]), np.stack([a, b, c]))
    assert rms == pytest.approx(2e-5 * math.sqrt(2.0 / 3.0), rel=1e-6)


def test_image_rms_is_the_pixel_residual_over_the_focal_length():
    camera = Camera.from_fov(512, 512, fov_deg=8.0)
    vectors = camera.pixel_to_vector(np.array([100.0, 300.0]), np.array([200.0, 50.0]))
    found = np.array([[100.3, 200.0], [300.0, 49.6]])  # residuals 0.3 and 0.4 px
    assert image_rms_rad(camera, found, vectors) == pytest.approx(math.sqrt((0.09 + 0.16) / 2) / camera.fx, rel=1e-9)


def test_noise_free_unsmeared_stars_are_centred_to_a_few_microradians():
    p = params(rate_deg_s=0.0, read_noise_e=0.0, sky_e=0.0, star_electrons=(5e4, 5e4))
    out = LEVEL.run(p, Rotation.from_euler("xy", [10.0, 20.0], degrees=True), np.random.default_rng(1), 5.0)
    row = out.row
    assert row["status"] == "OK" and row["n_matched"] >= 7 and row["correct"]
    # shot noise of 5e4 e- over a 1 px PSF: ~0.005 px per axis, about 1.5 urad
    assert row["sigma_urad"] < 0.05 * IFOV_URAD and row["std_urad"] < 0.05 * IFOV_URAD
    assert row["smear_px"] == 0.0


def test_the_smear_is_the_rate_times_the_exposure_at_most():
    p = params(rate_deg_s=0.25, exposure_s=0.03)
    row = LEVEL.run(p, Rotation.identity(), np.random.default_rng(7), 5.0).row
    bound = 0.25 * 0.03 * DEG * 1e6 / IFOV_URAD  # 0.48 px for a rate across the boresight
    assert 0.0 < row["smear_px"] <= bound * 1.001


def test_the_default_noise_gives_the_seed_baseline_within_a_quarter():
    rows = [LEVEL.run(params(rate_deg_s=0.0), Rotation.random(random_state=k), np.random.default_rng(k), 5.0).row
            for k in range(12)]
    sigma = math.sqrt(np.mean([r["sigma_urad"] ** 2 for r in rows]))
    assert 0.75 * 35.6 < sigma < 1.25 * 35.6  # urad: the seed's unsmeared sigma


def test_the_spec_holds_table_2():
    spec = shipped(SPEC)
    assert spec.sweep["exposure_s"] == (0.01, 0.02, 0.03) and len(spec.cells()) == 27
    sigma = seed_numbers(spec, "Samaan 2002 Table 2: interstar")
    std = seed_numbers(spec, "Samaan 2002 Table 2: image-plane")
    assert sigma[(("exposure_s", 0.01), ("rate_deg_s", 0.0))] == 35.6
    assert std[(("exposure_s", 0.01), ("rate_deg_s", 0.0))] == 39.1
    assert [sigma[(("exposure_s", 0.03), ("rate_deg_s", r))] for r in (0.01, 0.02, 0.05, 0.10, 0.15, 0.20, 0.25)] == [
        37.0, 38.2, 45.5, 81.9, 292.4, 521.0, 808.2]
    assert [std[(("exposure_s", 0.02), ("rate_deg_s", r))] for r in (0.01, 0.02, 0.05, 0.10, 0.15, 0.20, 0.25)] == [
        39.7, 42.0, 44.6, 52.4, 54.4, 228.0, 424.0]
    assert len(sigma) == len(std) == 22


def test_a_tiny_run_of_the_spec_gives_every_reference(tmp_path):
    trials, tables = tiny_run(SPEC, tmp_path, trials=1)
    assert trials.num_rows == 27
    for title, rows in tables.items():
        if title.startswith("Samaan 2002"):
            assert finite(rows), title
    again = rerun_trial(tmp_path / "out", 14, 0, save_dir=tmp_path / "frames")  # the image and its truth
    assert again.same and [f.suffix for f in again.files] == [".fits"]


def test_the_mle_centroider_beats_the_intensity_centroids_on_the_same_images():
    # Same trials (same streams), the seed's moments against startrack's MLE fit: unsmeared, 10 ms.
    rot = Rotation.from_euler("xy", [10.0, 20.0], degrees=True)
    sigma = {}
    for centroider in ("moments", "mle"):
        rows = [LEVEL.run(params(rate_deg_s=0.0, centroider=centroider), rot, np.random.default_rng(k), 5.0).row
                for k in range(8)]
        assert all(r["status"] == "OK" for r in rows)
        sigma[centroider] = float(np.sqrt(np.mean([r["sigma_urad"] ** 2 for r in rows])))
    assert sigma["mle"] < 0.8 * sigma["moments"]  # urad: the fit uses the PSF, the moments its noisy wings
    assert sigma["mle"] < 35.6  # urad, the seed's unsmeared interstar sigma
