"""The JSON API through a real server: a real image solved end to end, every result file, the
listing, status, options, OpenAPI, cameras and a simulated job against its truth."""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math

import numpy as np
import pytest
from astropy.io import fits
from astropy.wcs import WCS

from startrack.frames import angle_between, radec_to_vector
from startrack.units import ARCSEC, DEG

STAGES = ("read", "detect", "identify", "attitude", "refine", "annotate")


def wcs_of(content: bytes) -> WCS:
    """astropy's WCS of our header-only .wcs file (its image size is in IMAGEW / IMAGEH)."""
    header = fits.Header.fromstring(content.decode("ascii"))
    header["NAXIS"], header["NAXIS1"], header["NAXIS2"] = 2, header["IMAGEW"], header["IMAGEH"]
    return WCS(header)


def _truth_row(truth_table, name):
    return next(r for r in truth_table if r["file"] == name)


@pytest.fixture(scope="module")
def roof_job(server, real_images):
    response = server.submit(real_images["roof.jpg"])
    assert response.status_code == 201, response.text
    body = response.json()
    assert body["state"] == "queued" and response.headers["location"] == f"/api/jobs/{body['id']}"
    return server.wait_job(body["id"])


def test_a_real_image_solves_through_the_api_with_every_result_key(roof_job, truth_table):
    assert roof_job["state"] == "done", roof_job["error"]
    result = roof_job["result"]
    for key in ("status", "reason", "ra_deg", "dec_deg", "roll_deg", "fov_deg", "qx", "qy", "qz", "qw",
                "n_detected", "n_matched", "false_match_prob", "residual_arcsec", "times_s"):
        assert key in result
    assert result["status"] == "ok" and result["n_matched"] >= 8
    assert math.isclose(math.hypot(*(result[k] for k in ("qx", "qy", "qz", "qw"))), 1.0, abs_tol=1e-9)
    assert set(result["times_s"]) == set(STAGES)
    row = _truth_row(truth_table, "roof.jpg")
    assert abs((result["roll_deg"] - float(row["roll_tetra3_deg"]) + 180) % 360 - 180) < 0.2
    assert result["fov_deg"] == pytest.approx(float(row["fov_w_pinhole_deg"]), rel=0.01)
    assert set(roof_job["files"]) >= {"annotated.png", "solution.json", "solution.wcs", "matches.csv",
                                      "detections.csv", "rerun.json"}


def test_the_wcs_file_reads_back_with_astropy_at_the_true_centre(idle_server, roof_job, truth_table):
    response = idle_server.client.get(roof_job["files"]["solution.wcs"])
    assert response.status_code == 200 and response.headers["content-type"] == "application/fits"
    wcs = wcs_of(response.content)
    row = _truth_row(truth_table, "roof.jpg")
    width, height = int(row["width"]), int(row["height"])
    centre = wcs.pixel_to_world((width - 1) / 2, (height - 1) / 2)  # astropy's pixels are ours (0-based)
    truth = radec_to_vector(float(row["ra_center_deg"]) * DEG, float(row["dec_center_deg"]) * DEG)
    found = radec_to_vector(centre.ra.rad, centre.dec.rad)
    assert angle_between(found, truth) < 2 * float(row["pixscale_arcsec"]) * ARCSEC


def test_matches_csv_puts_each_star_where_the_wcs_says(idle_server, roof_job):
    rows = list(csv.DictReader(io.StringIO(idle_server.client.get(roof_job["files"]["matches.csv"]).text)))
    assert len(rows) == roof_job["result"]["n_matched"]
    assert list(rows[0]) == ["x", "y", "hip", "ra_deg", "dec_deg", "v_mag", "residual_arcsec"]
    wcs = wcs_of(idle_server.client.get(roof_job["files"]["solution.wcs"]).content)
    x, y, ra, dec = (np.array([float(r[k]) for r in rows]) for k in ("x", "y", "ra_deg", "dec_deg"))
    sky = wcs.pixel_to_world(x, y)
    cat = radec_to_vector(np.radians(ra), np.radians(dec))
    offsets = angle_between(radec_to_vector(sky.ra.rad, sky.dec.rad), cat) / ARCSEC
    residuals = np.array([float(r["residual_arcsec"]) for r in rows])
    assert np.all(np.abs(offsets - residuals) < 5.0)  # arcsec: the WCS is the fitted model
    assert all(int(r["hip"]) > 0 and 0 < float(r["v_mag"]) < 9 for r in rows)


def test_detections_csv_rerun_json_and_solution_json(idle_server, roof_job, real_images):
    client = idle_server.client
    detections = list(csv.DictReader(io.StringIO(client.get(roof_job["files"]["detections.csv"]).text)))
    assert len(detections) == roof_job["result"]["n_detected"]
    assert sum(1 for d in detections if d["hip"]) == roof_job["result"]["n_matched"]
    rerun = client.get(roof_job["files"]["rerun.json"]).json()
    assert rerun["input"]["sha256"] == hashlib.sha256(real_images["roof.jpg"].read_bytes()).hexdigest()
    assert rerun["options"]["fov_deg"] is None and rerun["options"]["detection_preset"] == "default"
    assert rerun["detector"]["sigma"] == 5.0
    assert rerun["startrack_version"]
    solution = client.get(roof_job["files"]["solution.json"]).json()
    assert solution["status"] == "ok" and len(solution["matches"]) == roof_job["result"]["n_matched"]
    png = client.get(roof_job["files"]["annotated.png"])
    assert png.headers["content-type"] == "image/png" and png.content.startswith(b"\x89PNG")


def test_a_current_copy_of_a_result_file_is_answered_304(idle_server, roof_job):
    """Before: the whole file again (200) for an If-None-Match naming its ETag."""
    client, url = idle_server.client, roof_job["files"]["annotated.png"]
    first = client.get(url)
    etag, modified = first.headers["etag"], first.headers["last-modified"]
    for headers in ({"If-None-Match": etag}, {"If-Modified-Since": modified}):
        again = client.get(url, headers=headers)
        assert again.status_code == 304 and again.content == b"" and again.headers["etag"] == etag, headers
    assert client.head(url, headers={"If-None-Match": etag}).status_code == 304
    changed = client.get(url, headers={"If-None-Match": '"another"', "If-Modified-Since": modified})
    assert changed.status_code == 200 and changed.content == first.content  # If-None-Match decides


def test_the_listing_the_page_and_deleting_a_finished_job(idle_server, real_images):
    client = idle_server.client
    job_id = idle_server.submit(real_images["crappy.jpg"]).json()["id"]
    idle_server.wait_job(job_id)
    listing = client.get("/api/jobs").json()
    assert listing["jobs"][0]["id"] == job_id and listing["count"] == len(listing["jobs"])
    assert client.get("/api/jobs", params={"state": "done"}).json()["count"] >= 1
    page = client.get(f"/jobs/{job_id}")
    assert page.status_code == 200 and "crappy.jpg" in page.text and "annotated.png" in page.text
    assert client.delete(f"/api/jobs/{job_id}").json() == {"id": job_id, "deleted": True}
    assert client.get(f"/api/jobs/{job_id}").status_code == 404
    again = idle_server.wait_job(idle_server.submit(real_images["crappy.jpg"]).json()["id"])
    removed = client.post(f"/jobs/{again['id']}/remove")  # the page's button
    assert removed.status_code == 303 and removed.headers["location"] == "/jobs"
    assert client.get(f"/api/jobs/{again['id']}").status_code == 404


def test_status_options_and_openapi(idle_server):
    client = idle_server.client
    status = client.get("/api/status").json()
    assert status["max_queued"] == 3 and status["folder_mode"] and len(status["workers"]) == 1
    options = client.get("/api/options").json()
    assert {p["name"] for p in options["detection_presets"]} >= {"default", "auto"}
    assert "night" in options["folders"] and "link_dir" not in options["folders"]
    assert any(c["name"] == "aptina-mt9p031" and c["distortion"] for c in options["cameras"])
    assert {a["name"] for a in options["analyses"]} >= {"histograms", "radial", "compare", "sweep"}
    assert options["limits"]["fov_deg"] == [0.5, 150.0]  # deg: a 12 mm lens's 113 deg is given (was 100 at most)
    assert options["limits"]["default_fov_range_deg"] == [3.0, 100.0]
    assert 'name="fov_deg" step="any" min="0.5" max="150"' in client.get("/").text
    analyses = client.get("/api/analyses").json()["analyses"]
    assert analyses == options["analyses"] and analyses[0]["params"] is not None
    doc = client.get("/api/openapi.json").json()
    assert doc["openapi"].startswith("3.1")
    assert {"/api/jobs", "/api/jobs/{job_id}", "/api/jobs/{job_id}/files/{name}", "/api/batches",
            "/api/analyses"} <= set(doc["paths"])
    assert set(doc["paths"]["/api/jobs"]["post"]["responses"]) == {"201", "400", "413", "415", "422", "429"}
    for page in ("/", "/jobs", "/batches", "/analyses", "/api"):
        response = client.get(page)
        assert response.status_code == 200 and "text/html" in response.headers["content-type"]
        assert response.headers["x-content-type-options"] == "nosniff"


def test_a_camera_profile_is_saved_and_fixes_the_focal_length(idle_server, real_images, truth_table):
    row = _truth_row(truth_table, "roof.jpg")
    focal = 206264.806 / float(row["pixscale_arcsec"])
    client = idle_server.client
    response = client.post("/api/cameras", json={"name": "roof-cam", "width": 507, "height": 507, "fx": focal})
    assert response.status_code == 201, response.text
    assert any(c["name"] == "roof-cam" and c["kind"] == "profile" for c in client.get("/api/cameras").json()["cameras"])
    job = idle_server.wait_job(idle_server.submit(real_images["roof.jpg"], {"camera": "roof-cam"}).json()["id"])
    assert job["state"] == "done", job["error"]
    assert job["result"]["focal_px"] == pytest.approx(focal, rel=1e-9)  # a camera fixes the focal length
    bad = client.post("/api/cameras", json={"name": "bad-cam", "width": 507, "height": 507, "fx": -3})
    assert bad.status_code == 422 and "focal length" in bad.json()["error"]
    assert client.post("/api/cameras", json={"name": "far-mst", "width": 9, "height": 9, "fx": 3}).status_code == 422
    # a preset's name spelled with '_' (which options.camera reads as the preset) is refused too
    hidden = client.post("/api/cameras", json={"name": "droid_x2", "width": 1024, "height": 1024, "fx": 1000})
    assert hidden.status_code == 422 and hidden.json()["field"] == "name"
    wrong = idle_server.wait_job(idle_server.submit(real_images["img3.png"], {"camera": "roof-cam"}).json()["id"])
    assert wrong["state"] == "failed" and "507 x 507 px but the image is 1392 x 1040 px" in wrong["error"]


def test_a_simulated_job_reports_its_error_against_the_truth(idle_server):
    scene = {"fov_deg": 12.0, "width": 640, "height": 480, "seed": 7, "max_mag": 7.0}
    response = idle_server.client.post("/api/jobs", files={"simulate": (None, json.dumps(scene))})
    assert response.status_code == 201, response.text
    job = idle_server.wait_job(response.json()["id"])
    assert job["state"] == "done", job["error"]
    truth = job["result"]["truth"]
    assert truth["error_px"] < 0.5  # the solve is within half a pixel of the simulator's attitude
    assert job["simulate"]["seed"] == 7 and job["input"]["format"] == "fits"
