"""The worker pool through a real server: cancellation (queued and running), the time limit, a
worker that dies mid-job, and a restart that keeps the finished jobs and fails the running one."""

from __future__ import annotations

import os
import shutil
import signal

from conftest import SLOW
from web_server import WebServer

from startrack.web.jobs import RESTART_REASON, JobStore
from startrack.web.options import validate_options


def test_cancel_a_queued_then_a_running_job(idle_server, random_field, real_images):
    client = idle_server.client
    restarts = client.get("/api/status").json()["restarts"]
    running = idle_server.submit(random_field, SLOW).json()["id"]
    idle_server.wait_job(running, states=("running",))
    queued = idle_server.submit(random_field, SLOW).json()["id"]
    assert client.get(f"/api/jobs/{queued}").json()["queue_position"] == 1
    assert client.delete(f"/api/jobs/{queued}").json() == {"id": queued, "state": "cancelled"}
    assert client.delete(f"/api/jobs/{running}").json() == {"id": running, "state": "cancelled"}
    for job_id in (queued, running):
        job = client.get(f"/api/jobs/{job_id}").json()
        assert job["state"] == "cancelled" and job["error"] is None and job["finished"]
    assert client.get("/api/status").json()["restarts"] == restarts + 1  # the running job's worker
    done = idle_server.wait_job(idle_server.submit(real_images["roof.jpg"]).json()["id"])
    assert done["state"] == "done"


def test_a_job_over_its_time_limit_fails_saying_so(idle_server, random_field):
    job = idle_server.wait_job(idle_server.submit(random_field, {**SLOW, "time_limit_s": 1}).json()["id"])
    assert job["state"] == "failed" and job["error"] == "timed out after 1 s"
    assert job["result"] is None and job["stage"] in ("identify", "detect", "read")


def test_a_worker_that_dies_fails_its_job_and_the_server_goes_on(idle_server, random_field, real_images):
    job_id = idle_server.submit(random_field, SLOW).json()["id"]
    idle_server.wait_job(job_id, states=("running",))
    status = idle_server.client.get("/api/status").json()
    [pid] = [w["pid"] for w in status["workers"] if w["job"] == job_id]
    os.kill(pid, signal.SIGKILL)
    job = idle_server.wait_job(job_id)
    assert job["state"] == "failed"
    assert job["error"] == ("the worker process stopped unexpectedly (exit code -9); the server started a new one")
    assert pid not in idle_server.worker_pids()
    after = idle_server.wait_job(idle_server.submit(real_images["crappy.jpg"]).json()["id"])
    assert after["state"] == "done"


def test_the_solvers_own_time_limit_is_a_failure_in_words(idle_server, random_field):
    job = idle_server.wait_job(idle_server.submit(random_field, SLOW).json()["id"])
    assert job["state"] == "failed" and job["result"]["status"] == "timeout"
    assert job["error"] == "timed out: no match within the 5 s time limit"
    assert job["result"]["failure"] == "timed out" and "annotated.png" in job["files"]


def _left_behind(store: JobStore, source, state: str) -> str:
    """A job as a server that died would leave it (the store the server uses, its own calls)."""
    job_id, folder = store.reserve()
    shutil.copy(source, folder / "input.jpg")
    store.create("solve", {"label": source.name, "input": "input.jpg", "options":
                           validate_options({}, store.root.parent / "cameras"), "batch": None}, job_id)
    if state == "running":
        store.set_state(job_id, state="running", stage="identify", started="2026-01-01T00:00:00+00:00")
    return job_id


def test_a_restart_fails_the_job_left_running_and_runs_the_one_left_queued(tmp_path, real_images):
    data = tmp_path / "data"
    store = JobStore(data / "jobs")
    running = _left_behind(store, real_images["roof.jpg"], "running")
    queued = _left_behind(store, real_images["tree.jpg"], "queued")
    server = WebServer(data)
    try:
        job = server.client.get(f"/api/jobs/{running}").json()
        assert job["state"] == "failed" and job["error"] == RESTART_REASON
        listed = {j["id"] for j in server.client.get("/api/jobs").json()["jobs"]}
        assert listed == {running, queued}
        assert server.wait_job(queued)["state"] == "done"
    finally:
        server.stop()
    assert server.process.returncode == 0
