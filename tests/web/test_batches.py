"""Result sets through a real server: several uploaded files, a folder under --root (and every
way out of it refused), a batch refused whole when one file is bad, and the analyses over sets."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest


def post_files(server, paths, options=None, name=None):
    files = [("file", (p.name, p.read_bytes())) for p in paths]
    data = {"options": json.dumps(options or {})}
    if name:
        data["name"] = name
    return server.client.post("/api/batches", files=files, data=data)


def wait_batch(server, batch_id):
    for job_id in server.client.get(f"/api/batches/{batch_id}").json()["jobs"]:
        server.wait_job(job_id["id"])
    return server.client.get(f"/api/batches/{batch_id}").json()


@pytest.fixture(scope="module")
def uploaded(server, real_images):
    response = post_files(server, [real_images["roof.jpg"], real_images["orion_trees.jpg"]], name="two JPEGs")
    assert response.status_code == 201, response.text
    return wait_batch(server, response.json()["id"])


@pytest.fixture(scope="module")
def folder_batch(server):
    response = server.client.post("/api/batches", files={"folder": (None, "night")})
    assert response.status_code == 201, response.text
    return response.json(), wait_batch(server, response.json()["id"])


def test_several_files_make_one_result_set(server, uploaded):
    assert uploaded["name"] == "two JPEGs" and uploaded["finished"] and uploaded["counts"] == {"done": 2}
    assert [j["label"] for j in uploaded["jobs"]] == ["roof.jpg", "orion_trees.jpg"]
    assert all(j["batch"] == uploaded["id"] for j in uploaded["jobs"])
    listed = server.client.get("/api/batches").json()["batches"]
    assert any(b["id"] == uploaded["id"] and b["n_jobs"] == 2 for b in listed)
    page = server.client.get(f"/batches/{uploaded['id']}")
    assert page.status_code == 200 and "orion_trees.jpg" in page.text and "Analyse this result set" in page.text


def test_a_folder_under_root_is_a_result_set_without_the_link_out(folder_batch):
    created, batch = folder_batch
    assert created["skipped"] == ["zz_link_out.png: a link out of --root"]
    assert batch["source"] == {"kind": "folder", "folder": "night", "skipped": created["skipped"]}
    assert sorted(j["label"] for j in batch["jobs"]) == ["roof.jpg", "tree.jpg"]
    assert batch["counts"] == {"done": 2}


@pytest.mark.parametrize("folder", ["..", "../..", "/etc", "night/../..", "link_dir", "empty", "missing",
                                    "night/roof.jpg"])
def test_folders_outside_root_or_without_images_are_404(server, folder):
    before = len(server.client.get("/api/jobs").json()["jobs"])
    response = server.client.post("/api/batches", files={"folder": (None, folder)})
    assert response.status_code == 404 and "error" in response.json()
    assert len(server.client.get("/api/jobs").json()["jobs"]) == before


def test_one_bad_file_refuses_the_whole_batch(server, real_images, tmp_path):
    bad = tmp_path / "notes.png"
    bad.write_text("not an image")
    before = len(server.client.get("/api/jobs").json()["jobs"])
    response = post_files(server, [real_images["roof.jpg"], bad])
    assert response.status_code == 415 and "'notes.png'" in response.json()["error"]
    assert len(server.client.get("/api/jobs").json()["jobs"]) == before
    folders = list((server.data_dir / "jobs").iterdir())
    assert all((p / "job.json").exists() for p in folders)  # the accepted file's folder was removed too


def test_a_batch_larger_than_the_queue_is_429(idle_server, real_images):
    response = post_files(idle_server, [real_images["roof.jpg"]] * 4)  # --max-queued 3
    assert response.status_code == 429 and "4 more asked" in response.json()["error"]


def test_an_analysis_over_one_set_writes_its_figure_and_numbers(server, uploaded):
    body = {"analysis": "radial", "sets": [{"batch": uploaded["id"]}]}
    response = server.client.post("/api/analyses", json=body)
    assert response.status_code == 201, response.text
    job = server.wait_job(response.json()["id"])
    assert job["state"] == "done" and job["kind"] == "analysis", job["error"]
    result = job["result"]
    assert result["figure"] == "radial.png" and "radial.png" in job["files"]
    stars = list(csv.DictReader(io.StringIO(server.client.get(job["files"]["radial_stars.csv"]).text)))
    matched = sum(j["n_matched"] for j in uploaded["jobs"])
    assert len(stars) == matched  # one row per matched star of the set's jobs
    residuals = np.array([float(s["residual_arcsec"]) for s in stars])
    expected = [server.client.get(f"/api/jobs/{j['id']}").json()["result"]["residual_arcsec"] for j in uploaded["jobs"]]
    assert np.sqrt(np.mean(residuals**2)) == pytest.approx(
        np.sqrt(np.average(np.square(expected), weights=[j["n_matched"] for j in uploaded["jobs"]])), rel=1e-9)
    assert server.client.get(f"/jobs/{job['id']}").status_code == 200


def test_an_analysis_over_two_sets_reads_the_pixels_of_the_uploads(server, uploaded, folder_batch):
    _, folder = folder_batch
    body = {"analysis": "gallery", "params": {}, "sets": [{"batch": uploaded["id"]},
                                                          {"name": "tree only", "jobs": [folder["jobs"][1]["id"]]}]}
    job = server.wait_job(server.client.post("/api/analyses", json=body).json()["id"])
    assert job["state"] == "done", job["error"]
    assert job["analysis"]["sets"][1]["name"] == "tree only" and job["result"]["figure"] == "gallery.png"


@pytest.mark.parametrize(("body", "status", "field"), [
    ({"analysis": "astrology", "sets": []}, 422, "analysis"),
    ({"analysis": "compare", "sets": [{"batch": "0" * 32}]}, 422, "sets"),
    ({"analysis": "radial", "sets": [{"jobs": []}]}, 422, "sets[0].jobs"),
    ({"analysis": "radial", "sets": [{"jobs": ["0" * 32]}]}, 404, None),
    ({"analysis": "radial", "sets": [{"batch": "../../etc"}]}, 404, None),
    ({"analysis": "sweep", "sets": [{"jobs": ["0" * 32]}], "params": {"setting": "colour"}}, 422, "params"),
    ({"analysis": "radial", "sets": "all"}, 422, "sets"),
    ({"analysis": "radial", "sets": [{"jobs": ["0" * 32]}], "extra": 1}, 422, "extra"),
])
def test_analysis_refusals(server, body, status, field):
    response = server.client.post("/api/analyses", json=body)
    assert response.status_code == status, response.text
    assert response.json().get("field") == field


def test_an_analysis_job_is_not_a_set_and_the_body_must_be_json(idle_server, uploaded):
    analysis = next(j for j in idle_server.client.get("/api/jobs").json()["jobs"] if j["kind"] == "analysis")
    response = idle_server.client.post("/api/analyses", json={"analysis": "radial",
                                                              "sets": [{"jobs": [analysis["id"]]}]})
    assert response.status_code == 422 and "is an analysis" in response.json()["error"]
    assert idle_server.client.post("/api/analyses", content=b"{", headers={"content-type": "application/json"}
                                   ).status_code == 400
    assert idle_server.client.post("/api/analyses", data={"analysis": "radial"}).status_code == 415
