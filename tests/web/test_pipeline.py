"""What a solve job computes, checked on the job's own folder: the auto preset and camera fit on a
real image, the solution kept on disk and the analysis record made from it, a ground photo's
altitude and azimuth against astropy, a blank frame's failure in words; and, without a server,
the spots the detector refused with their reasons."""

from __future__ import annotations

import csv
import json
import warnings

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import AltAz, EarthLocation, SkyCoord
from astropy.time import Time
from astropy.utils import iers

from startrack.calibrate._sites import get_site
from startrack.detect import StarDetector
from startrack.frames import angle_between, radec_to_vector
from startrack.io import write_png
from startrack.results import AttitudeSolution, Detections, Status
from startrack.units import ARCSEC, DEG
from startrack.web._annotate import grid_step_deg, residual_gain
from startrack.web._jobs import read_json
from startrack.web._outputs import failure_words
from startrack.web._records import job_record, load_solution
from startrack.web._rejects import rejected_spots, without_solved


def run_job(server, source, options: dict | None = None):
    """Solve ``source`` on the session's server; the job's folder (on this machine)."""
    job = server.wait_job(server.submit(source, options).json()["id"])
    return server.data_dir / "jobs" / job["id"]


def centre_error_px(solution: AttitudeSolution, row: dict) -> float:
    """Angle between the solved and the true direction of the image centre, in true pixels."""
    width, height = int(row["width"]), int(row["height"])
    centre_cam = solution.camera.pixel_to_vector((width - 1) / 2, (height - 1) / 2)
    centre = solution.rot_cam_from_icrs.inv().apply(centre_cam)
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    return float(angle_between(centre, truth) / (float(row["pixscale_arcsec"]) * ARCSEC))


@pytest.fixture(scope="module")
def auto_job(server, real_images):
    return run_job(server, real_images["img3.png"], {"detection_preset": "auto"})


def test_auto_preset_sets_the_detector_from_the_image_and_fits_the_camera(auto_job, truth_table):
    state, result = read_json(auto_job / "state.json"), read_json(auto_job / "result.json")
    assert state["state"] == "done" and state["progress"] == 1.0
    auto = result["auto"]
    assert 4.0 <= auto["sigma"] <= 50.0 and 2 <= auto["min_area_px"] <= 9 and auto["probe_spots"] > 0
    fit = result["camera_fit"]
    assert fit["kept"] and "f" in fit["fitted"] and fit["matches_after"] >= fit["matches_before"]
    row = next(r for r in truth_table if r["file"] == "img3.png")
    assert result["fov_deg"] == pytest.approx(float(row["fov_w_pinhole_deg"]), rel=0.01)
    assert centre_error_px(load_solution(auto_job / "record.npz")[0], row) < 2.0
    rerun = read_json(auto_job / "rerun.json")
    assert rerun["detector"]["sigma"] == pytest.approx(auto["sigma"]) and rerun["auto"] == auto


def test_the_solution_on_disk_rebuilds_the_analysis_record(auto_job):
    result = read_json(auto_job / "result.json")
    solution, extra = load_solution(auto_job / "record.npz")
    assert isinstance(solution, AttitudeSolution) and solution.solved
    np.testing.assert_allclose(solution.quaternion_xyzw, [result[k] for k in ("qx", "qy", "qz", "qw")], atol=1e-12)
    assert len(solution.detections) == result["n_detected"] and len(solution.matches) == result["n_matched"]
    with open(auto_job / "matches.csv", newline="") as fh:
        assert [int(r["hip"]) for r in csv.DictReader(fh)] == solution.matches.hip.tolist()
    record = job_record(auto_job)
    assert record.name == "img3.png" and record.path.is_file() and record.image is None
    assert record.settings["detector"]["sigma"] == pytest.approx(result["auto"]["sigma"])
    assert record.camera is not None and record.camera.fx == pytest.approx(result["focal_px"])
    assert extra["epoch_jyear"] == 2000.0
    assert solution.fov_source == result["fov_source"] == "camera"  # the last solve, with the camera it fitted


def test_a_mirror_image_is_solved_and_said_to_be(server, real_images, tmp_path):
    from PIL import Image

    grey = np.asarray(Image.open(real_images["crappy.jpg"]).convert("L"))
    flipped = tmp_path / "crappy-flipped.png"
    write_png(flipped, np.ascontiguousarray(grey[:, ::-1]))
    result = read_json(run_job(server, flipped) / "result.json")
    assert result["status"] == "ok" and result["mirrored"] is True
    unflipped = read_json(run_job(server, real_images["crappy.jpg"]) / "result.json")
    assert unflipped["status"] == "ok" and unflipped["mirrored"] is False
    assert result["constellation"] == unflipped["constellation"] == "Taurus"  # as astropy's get_constellation says


def test_the_guided_option_adds_the_stars_the_solution_predicts(server, real_images):
    """roof.jpg: the guided pass measures 3 catalog stars where nothing was detected
    (docs/identification.md); the result counts them, the page says so and the record keeps them."""
    folder = run_job(server, real_images["roof.jpg"], {"guided": True})
    result = read_json(folder / "result.json")
    plain = read_json(run_job(server, real_images["roof.jpg"]) / "result.json")
    assert result["status"] == plain["status"] == "ok" and plain["guided_stars"] == 0
    assert result["guided_stars"] >= 2 and result["n_matched"] == plain["n_matched"] + result["guided_stars"]
    assert result["n_detected"] == plain["n_detected"] + result["guided_stars"]
    assert load_solution(folder / "record.npz")[0].guided_stars == result["guided_stars"]
    with open(folder / "detections.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["guided"] for r in rows].count("true") == result["guided_stars"]
    assert all(r["hip"] and not r["mag"] for r in rows if r["guided"] == "true")
    page = server.client.get(f"/jobs/{folder.name}").text
    assert f"{result['guided_stars']} of them measured where the solution predicts them" in page


def test_a_bayer_mosaic_fits_is_solved_at_full_resolution_and_said_to_be(server, real_images, tmp_path):
    """img3.png through an RGGB mosaic (R, G, B passing 0.45, 1.0, 0.6 of the light above the sky),
    saved as FITS with BAYERPAT: solved, the result and the page name the pattern, and the stars lie
    where the grey image has them (full resolution, not 2 x 2 cells)."""
    from astropy.io import fits
    from PIL import Image

    grey = np.asarray(Image.open(real_images["img3.png"]).convert("L"), dtype=np.float64)
    h, w = grey.shape
    sky = float(np.median(grey))
    mosaic = (grey - sky) * np.tile(np.array([[0.45, 1.0], [1.0, 0.6]]), (h // 2 + 1, w // 2 + 1))[:h, :w] + sky
    path = tmp_path / "osc.fits"
    fits.PrimaryHDU(np.clip(mosaic * 16, 0, 65535).astype(np.uint16), fits.Header([("BAYERPAT", "RGGB")])).writeto(path)
    folder = run_job(server, path)
    result = read_json(folder / "result.json")
    assert result["status"] == "ok" and result["mosaic"] == "RGGB"
    page = server.client.get(f"/jobs/{folder.name}").text
    assert "a colour-filter (Bayer) mosaic (pattern RGGB)" in page
    plain_folder = run_job(server, real_images["img3.png"])
    assert read_json(plain_folder / "result.json")["mosaic"] is None
    stars, plain_stars = (_detected_xy(f) for f in (folder, plain_folder))
    for x, y in plain_stars[:5]:  # the five brightest, where the grey frame has them (full-resolution px)
        assert np.min(np.hypot(stars[:, 0] - x, stars[:, 1] - y)) < 0.5


def _detected_xy(folder) -> np.ndarray:
    """(x, y) of a job's detections, shape (N, 2), in the order of its detections.csv."""
    with open(folder / "detections.csv", newline="") as fh:
        return np.array([(float(r["x"]), float(r["y"])) for r in csv.DictReader(fh)])


def test_a_ground_photo_has_the_altitude_and_azimuth_astropy_gives(server, real_images):
    when, site = "2021-02-01T04:00:00", get_site("logan-ut")
    folder = run_job(server, real_images["roof.jpg"], {"site": "logan-ut", "time": when})
    result = read_json(folder / "result.json")
    assert result["status"] == "ok" and result["site"] == "logan-ut" and result["time_utc"].startswith(when)
    location = EarthLocation(lat=site.latitude_deg * u.deg, lon=site.longitude_deg * u.deg, height=site.height_m * u.m)
    frame = AltAz(obstime=Time(when, scale="utc"), location=location, pressure=site.pressure * 10 * u.hPa,
                  temperature=site.temperature_c * u.deg_C, relative_humidity=0.0, obswl=0.55 * u.micron)
    with iers.conf.set_temp("auto_download", False), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # astropy's notes on its offline IERS table
        seen = SkyCoord(ra=result["ra_deg"] * u.deg, dec=result["dec_deg"] * u.deg).transform_to(frame)
    assert seen.alt.deg > 30
    assert result["altitude_deg"] == pytest.approx(seen.alt.deg, abs=0.01)
    assert result["azimuth_deg"] == pytest.approx(seen.az.deg, abs=0.01 / np.cos(np.radians(seen.alt.deg)))


def test_a_blank_frame_fails_saying_no_stars_were_found(server, tmp_path):
    blank = tmp_path / "blank.png"
    write_png(blank, np.full((120, 160), 200, dtype=np.uint16))
    folder = run_job(server, blank)
    state, result = read_json(folder / "state.json"), read_json(folder / "result.json")
    assert state["state"] == "failed" and state["error"].startswith("no stars found: ")
    assert result["status"] == "too_few_stars" and result["failure"] == "no stars found"
    assert (folder / "annotated.png").is_file() and not (folder / "solution.wcs").exists()


def test_refused_spots_carry_the_filter_that_refused_them():
    rng = np.random.default_rng(0)
    yy, xx = np.mgrid[0:200, 0:200]
    image = rng.normal(100.0, 3.0, (200, 200))
    for x, y, amplitude in ((60, 60, 800), (140, 50, 600), (100, 0.2, 900)):  # the last at the top edge
        image += amplitude * np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * 1.3**2))
    image[120, 120] += 2000  # a hot pixel
    image[150:153, 30:90] += 300  # a line, not a star
    detector = StarDetector()
    kept = detector.detect(image)
    refused = rejected_spots(image, detector, kept)
    found = {(round(x), round(y)): c for x, y, c in zip(refused["x"], refused["y"], refused["category"], strict=True)}
    assert found[(120, 120)] == "hot pixel" and found[(100, 1)] == "edge"
    assert [c for (x, y), c in found.items() if 140 <= y <= 160] == ["elongation"]
    assert len(kept) == 2 and not any(abs(x - 60) < 2 and abs(y - 60) < 2 for x, y in found)


def test_failure_words():
    assert failure_words(AttitudeSolution(status=Status.TOO_FEW_STARS), 0) == "no stars found"
    assert failure_words(AttitudeSolution(status=Status.TOO_FEW_STARS), 3) == "too few stars (3 found)"
    assert failure_words(AttitudeSolution(status=Status.NO_MATCH), 30) == "no pattern matched"
    assert failure_words(AttitudeSolution(status=Status.TIMEOUT), 30) == "timed out"
    assert failure_words(AttitudeSolution(status=Status.DEGENERATE), 30) == "ambiguous"


def test_residual_magnification_and_grid_spacing_are_round():
    assert residual_gain(np.array([0.5, 1.0, 1.5]), 500) == 20.0  # 4 % of 500 px over a 1 px median
    assert residual_gain(np.array([0.0]), 500) == 1.0
    assert grid_step_deg(10.2) == 5.0 and grid_step_deg(6.0) == 2.0 and grid_step_deg(60.0) == 15.0


def test_a_refused_job_options_file_is_plain_json(auto_job):
    meta = json.loads((auto_job / "job.json").read_text())
    assert meta["options"]["detection_preset"] == "auto" and meta["options"]["fit_camera"] is True


def test_pairs_of_hot_pixels_are_named_as_hot_where_hot_pixels_abound():
    """The detector refuses two hot pixels side by side where single ones abound; the list of
    refused spots names them so (before: "another filter")."""
    rng = np.random.default_rng(1)
    image = rng.normal(100.0, 3.0, (300, 300))
    cells = rng.permutation(np.stack(np.mgrid[1:14, 1:14], -1).reshape(-1, 2))[:45] * 20 + 10  # px, apart
    for y, x in cells[:40]:
        image[y, x] += 3000.0  # single hot pixels
    pairs = cells[40:]
    for y, x in pairs:
        image[y, x] += 3000.0
        image[y, x + 1] += 2900.0  # its neighbour
    detector = StarDetector()
    refused = rejected_spots(image, detector, detector.detect(image))
    found = {(round(x), round(y)): c for x, y, c in zip(refused["x"], refused["y"], refused["category"], strict=True)}
    near_px = 1  # a refused spot within 1 px of a pair's middle is that pair
    named = [c for (x, y), c in found.items()
             if any(abs(y - py) <= near_px and abs(x - px - 0.5) <= near_px for py, px in pairs)]
    assert named and all(c == "hot pixel" for c in named), found


def test_pairs_alone_are_named_as_hot_where_they_abound():
    """Pairs of hot pixels with no single ones among them: the detector counts the pairs when it
    decides that hot pixels abound, and so does the list of refused spots (before: it counted
    single hot pixels only and named the pairs "another filter")."""
    rng = np.random.default_rng(2)
    yy, xx = np.mgrid[0:300, 0:300]
    image = rng.normal(100.0, 3.0, (300, 300))
    cells = rng.permutation(np.stack(np.mgrid[1:14, 1:14], -1).reshape(-1, 2))[:45] * 20 + 10  # px, apart
    for y, x in cells[:40]:
        image[y, x] += 3000.0
        image[y, x + 1] += 2900.0  # a pair
    for y, x in cells[40:]:  # five stars
        image += 2000.0 * np.exp(-((xx - x - 5.3) ** 2 + (yy - y - 5.6) ** 2) / (2 * 1.3**2))
    detector = StarDetector()
    kept = detector.detect(image)
    refused = rejected_spots(image, detector, kept)
    found = {(round(x), round(y)): c for x, y, c in zip(refused["x"], refused["y"], refused["category"], strict=True)}
    near_px = 1  # a refused spot within 1 px of a pair's middle is that pair
    named = [c for (x, y), c in found.items()
             if any(abs(y - py) <= near_px and abs(x - px - 0.5) <= near_px for py, px in cells[:40])]
    assert len(kept) == 5 and len(named) == 40 and set(named) == {"hot pixel"}, (len(kept), found)


def test_a_refused_spot_the_solve_used_is_not_listed_as_refused():
    """Where the detector's spots matched nothing, solve_image solves again on the spots found
    with the clutter test off; those it then holds are detections, not refused spots."""
    rejects = {"x": [10.0, 50.0, 90.0], "y": [10.0, 50.0, 90.0], "category": ["clutter", "clutter", "edge"]}
    solved = Detections(x=np.array([50.4, 200.0]), y=np.array([49.5, 200.0]))
    assert without_solved(rejects, solved) == {"x": [10.0, 90.0], "y": [10.0, 90.0], "category": ["clutter", "edge"]}
    assert without_solved(rejects, None) is rejects


def test_detections_csv_keeps_the_detect_stage_measurements_only_for_its_own_spots():
    """The detect stage's magnitudes go with the solution's detections when those are its spots;
    a second detection (star trails: weighted centroids of as many spots) gets none."""
    from startrack.detect._details import DetectionDetails
    from startrack.web._outputs import detections_table

    spots = Detections(x=np.array([10.0, 50.0]), y=np.array([20.0, 60.0]))
    details = DetectionDetails(detections=spots, mag=np.array([3.0, 4.0]), peak_snr=np.array([50.0, 20.0]),
                               psf_sigma_px=np.array([1.2, 1.3]))
    same = detections_table(details, AttitudeSolution(status=Status.NO_MATCH, detections=spots))
    moved = Detections(x=np.array([10.4, 50.0]), y=np.array([20.0, 60.0]))
    other = detections_table(details, AttitudeSolution(status=Status.NO_MATCH, detections=moved))
    assert same["mag"] == [3.0, 4.0] and other["mag"] == [None, None] and other["x"] == [10.4, 50.0]
