"""The numbers of the analyses that read records (histograms, gallery, radial, magnitude,
compare, thresholds, sweep), each against an independent computation from the solutions, the
detector or numpy, on simulated frames with a few noise blobs added (spots no star explains)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from startrack import Camera
from startrack.analysis._records import ImageRecord
from startrack.analysis.postprocess import ResultSet, run_analysis
from startrack.analysis.postprocess._radial import quadratic_fit
from startrack.catalog import load_catalog
from startrack.detect import StarDetector
from startrack.frames import angle_between, boresight, random_rotations
from startrack.results import AttitudeSolution, Detections, StarMatches, Status
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.solve import solve_image

CAMERA = Camera.from_fov(448, 384, 12.0)
FOV_DEG = 12.0
N_BLOBS = 4


def _with_blobs(image: np.ndarray, truth, rng: np.random.Generator) -> np.ndarray:
    """Add N_BLOBS compact Gaussian blobs (sigma 1.2 px, peak 600 ADU) at random places at least
    15 px from every star, so that no star's spot is blended with one."""
    yy, xx = np.mgrid[0:image.shape[0], 0:image.shape[1]]
    out = image.astype(np.float64)
    placed = 0
    while placed < N_BLOBS:
        x, y = rng.uniform(20, CAMERA.width - 20), rng.uniform(20, CAMERA.height - 20)
        if np.min(np.hypot(truth.x - x, truth.y - y)) < 15.0:
            continue
        out += 600.0 * np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * 1.2**2))
        placed += 1
    return np.clip(np.round(out), 0, 65535).astype(np.uint16)


@pytest.fixture(scope="module")
def sim_set() -> ResultSet:
    sensor = get_sensor_preset("generic-cmos")
    rng = np.random.default_rng(3)
    records = []
    for i, truth in enumerate(random_rotations(4, rng=21)):
        sim = simulate_frame(CAMERA, truth, max_mag=7.0, sensor=sensor, rng=i)
        image = _with_blobs(sim.image, sim.truth, rng)
        solution = solve_image(image, fov_deg=FOV_DEG)
        assert solution.solved, solution.reason
        records.append(ImageRecord(f"frame{i}.fits", solution, image=image, truth=sim.truth,
                                   settings={"fov_deg": FOV_DEG, "detector": {}}))
    return ResultSet("sim", tuple(records))


def test_spot_histograms_count_every_star_and_noise_spot_on_shared_bins(sim_set):
    result = run_analysis("histograms", [sim_set], {"bins": 12})
    hist = result.tables["spot_histograms"]
    for quantity in ("flux", "area_px", "elongation"):
        for kind in ("star", "noise"):
            values = np.concatenate([_spot_values(r.solution, quantity, kind) for r in sim_set.records])
            rows = [i for i, (q, k) in enumerate(zip(hist["quantity"], hist["spot"], strict=True))
                    if q == quantity and k == kind]
            edges = np.append([hist["bin_low"][i] for i in rows], hist["bin_high"][rows[-1]])
            assert [hist["count"][i] for i in rows] == list(np.histogram(values, bins=edges)[0])
            assert sum(hist["count"][i] for i in rows) == values.size
    counts = result.tables["counts"]
    assert counts["n_star"] == [len(r.solution.matches) for r in sim_set.records]
    assert sum(counts["n_noise"]) >= N_BLOBS * len(sim_set.records)
    image_hist = result.tables["image_histogram"]
    pixels = np.concatenate([r.image.ravel() for r in sim_set.records])
    edges = np.append(image_hist["bin_low"], image_hist["bin_high"][-1])
    assert image_hist["count"] == list(np.histogram(pixels, bins=edges)[0])
    assert result.summary["sim: noise spots per image"] == pytest.approx(np.mean(counts["n_noise"]))


def _spot_values(solution: AttitudeSolution, quantity: str, kind: str) -> np.ndarray:
    det = solution.detections
    star = np.isin(np.arange(len(det)), solution.matches.det_index)
    return getattr(det, quantity)[star if kind == "star" else ~star].astype(float)


def test_gallery_shows_matched_stars_as_stars_and_the_rest_as_noise_with_the_image_pixels(sim_set):
    result = run_analysis("gallery", [sim_set], {"count": 5, "stamp_px": 9, "seed": 4})
    stamps = result.tables["stamps"]
    assert stamps["spot"].count("star") == 5 and stamps["spot"].count("noise") == 5
    by_name = {r.name: r for r in sim_set.records}
    for i, kind in enumerate(stamps["spot"]):
        record = by_name[stamps["record"][i]]
        index, matches = stamps["index"][i], record.solution.matches
        if kind == "star":
            assert stamps["hip"][i] == matches.hip[list(matches.det_index).index(index)]
        else:
            assert index not in matches.det_index and stamps["hip"][i] is None
        x, y = round(record.solution.detections.x[index]), round(record.solution.detections.y[index])
        window = record.image[max(y - 4, 0):y + 5, max(x - 4, 0):x + 5]
        assert stamps["stamp_max"][i] == window.max() and stamps["stamp_min"][i] == window.min()
    again = run_analysis("gallery", [sim_set], {"count": 5, "stamp_px": 9, "seed": 4}).tables["stamps"]
    other = run_analysis("gallery", [sim_set], {"count": 5, "stamp_px": 9, "seed": 5}).tables["stamps"]
    assert again["index"] == stamps["index"] and other["index"] != stamps["index"]


def test_radial_fit_agrees_with_numpy_polyfit_and_its_covariance(sim_set):
    result = run_analysis("radial", [sim_set])
    stars = result.tables["stars"]
    solutions = [r.solution for r in sim_set.records]
    residual = np.concatenate([s.residuals_arcsec for s in solutions])
    radius = np.concatenate([np.hypot(s.detections.x[s.matches.det_index] - s.camera.cx,
                                      s.detections.y[s.matches.det_index] - s.camera.cy) for s in solutions])
    np.testing.assert_array_equal(stars["residual_arcsec"], residual)
    np.testing.assert_allclose(stars["radius_px"], radius, atol=1e-9)
    coef, cov = np.polyfit(radius, residual, 2, cov=True)
    fit = result.tables["fit"]
    np.testing.assert_allclose(fit["value"], coef[::-1], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(fit["sigma"], np.sqrt(np.diag(cov))[::-1], rtol=1e-8)
    assert fit["coefficient"] == ["c0", "c1", "c2"] and fit["n_stars"] == [radius.size] * 3


def test_quadratic_fit_recovers_an_exact_trend_and_needs_four_points():
    r = np.linspace(0, 300, 20)
    coef, sigma = quadratic_fit(r, 2.0 + 0.01 * r + 3e-5 * r**2)
    np.testing.assert_allclose(coef, [2.0, 0.01, 3e-5], rtol=1e-9)
    assert np.all(sigma < 1e-9)
    assert np.all(np.isnan(quadratic_fit(r[:3], r[:3])[0]))


def test_magnitude_uses_the_catalog_magnitude_and_finds_a_linear_detector(sim_set):
    result = run_analysis("magnitude", [sim_set])
    stars = result.tables["stars"]
    catalog = load_catalog()
    rows = [int(np.flatnonzero(catalog.hip == hip)[0]) for hip in stars["hip"][:10]]
    np.testing.assert_array_equal(stars["mag_v"][:10], catalog.v_mag[rows])
    flux, mag = stars["flux"], stars["mag_v"]
    assert result.summary["sim: zero point, mag"] == pytest.approx(np.median(mag + 2.5 * np.log10(flux)))
    # a linear detector: log10(volume) falls by 0.4 per magnitude (to 0.015 on some 110 stars; the
    # simulator's own electrons give -0.400 on them, its saturated few flatten the measured slope a little)
    assert result.summary["sim: slope of log10(volume), per mag"] == pytest.approx(-0.4, abs=0.015)
    per_image = result.tables["per_image"]
    assert per_image["n_stars"] == [len(r.solution.matches) for r in sim_set.records]


def test_compare_gives_the_boresight_angle_and_roll_difference_of_the_solutions(sim_set):
    changed = []
    for r in sim_set.records[:3]:
        solution = solve_image(r.image, fov_deg=FOV_DEG, detector=StarDetector(max_stars=16))
        changed.append(replace(r, solution=solution))
    failed = ImageRecord("only-in-b.fits", AttitudeSolution(status=Status.NO_MATCH, reason="no pattern"))
    result = run_analysis("compare", [sim_set, ResultSet("brightest16", (*changed, failed))])
    table = result.tables["images"]
    assert table["record"] == [r.name for r in sim_set.records] + ["only-in-b.fits"]
    assert table["in_b"] == [True, True, True, False, True] and table["in_a"] == [True] * 4 + [False]
    for i, (a, b) in enumerate(zip(sim_set.records[:3], changed, strict=True)):
        rot_a, rot_b = a.solution.rot_cam_from_icrs, b.solution.rot_cam_from_icrs
        expected = float(np.degrees(angle_between(boresight(rot_a), boresight(rot_b))) * 3600)
        assert table["pointing_diff_arcsec"][i] == pytest.approx(expected, rel=1e-9, abs=1e-9)
        roll = np.degrees((rot_b * rot_a.inv()).as_rotvec()[2]) * 3600
        assert table["roll_diff_arcsec"][i] == pytest.approx(roll, rel=1e-9, abs=1e-9)
        assert table["matches_b"][i] == len(b.solution.matches)
        assert 0 < table["pointing_diff_arcsec"][i] < 60.0  # a different star set moves it by much less than a pixel
    assert np.isnan(table["pointing_diff_arcsec"][3]) and table["solved_b"][4] is False
    assert result.summary["solved in both"] == 3
    itself = run_analysis("compare", [sim_set, sim_set]).tables["images"]
    assert max(itself["total_diff_arcsec"]) == 0.0


def test_threshold_comparison_matches_the_detector_and_solver_run_directly(sim_set):
    sigmas = [4.0, 5.0, 10.0]
    records = sim_set.records[:2]
    result = run_analysis("thresholds", [ResultSet("two", records)], {"sigmas": sigmas})
    images = result.tables["images"]
    assert images["value"] == sigmas * 2
    for row, (record, k) in enumerate((r, k) for r in records for k in sigmas):
        direct = solve_image(record.image, fov_deg=FOV_DEG, detector=StarDetector(sigma=k))
        assert images["n_detected"][row] == len(direct.detections)
        assert images["n_matched"][row] == len(direct.matches)
        assert images["residual_rms_arcsec"][row] == pytest.approx(np.sqrt(np.mean(direct.residuals_arcsec**2)))
    assert images["n_detected"][0] > images["n_detected"][2]  # a higher threshold finds fewer spots
    # at the records' own threshold (5 sigma) the same stars come back with the same residuals
    assert images["n_common"][1] == len(records[0].solution.matches) and images["residual_change_arcsec"][1] == 0
    per_k = result.tables["thresholds"]
    assert per_k["success_rate"] == [1.0, 1.0, 1.0]
    assert per_k["mean_detected"][2] == pytest.approx(np.mean(images["n_detected"][2::3]))


def test_sweep_over_min_area_counts_what_the_detector_keeps(sim_set):
    record = sim_set.records[0]
    result = run_analysis("sweep", [ResultSet("one", (record,))], {"setting": "min_area_px", "values": [2, 40, 200]})
    images = result.tables["images"]
    for row, area in enumerate((2, 40, 200)):
        assert images["n_detected"][row] == len(StarDetector(min_area_px=area).detect(record.image))
    assert images["n_detected"][0] >= images["n_detected"][1] > images["n_detected"][2]
    floats = run_analysis("sweep", [ResultSet("one", (record,))], {"setting": "sigma", "values": [5, 9]})
    assert floats.tables["values"]["value"] == [5.0, 9.0]


def test_analyses_without_matched_stars_still_give_a_figure():
    det = Detections(x=np.array([10.0]), y=np.array([12.0]), flux=np.array([50.0]), sigma_px=np.array([0.1]),
                     area_px=np.array([5]), peak=np.array([20.0]), elongation=np.array([1.1]), width=64, height=48)
    solution = AttitudeSolution(status=Status.NO_MATCH, reason="no pattern", detections=det,
                                matches=StarMatches(status=Status.NO_MATCH))
    only = ResultSet("noise", (ImageRecord("n.png", solution, image=np.zeros((48, 64), np.uint16)),))
    for name in ("histograms", "gallery", "radial", "magnitude", "corrections"):
        result = run_analysis(name, [only])
        assert result.figure.axes, name
    assert run_analysis("gallery", [only]).tables["stamps"]["spot"] == ["noise"]
