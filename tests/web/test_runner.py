"""The worker pool through a real server: cancellation (queued and running), the time limit, a
worker that dies mid-job, and a restart that keeps the finished jobs and fails the running one."""

from __future__ import annotations

import os
import shutil
import signal

from web_server import WebServer

from conftest import SLOW
from startrack.web._jobs import RESTART_REASON, JobStore
from startrack.web._options import validate_options


def test_cancel_a_running_job(idle_server, random_field, real_images):
    client = idle_server.client
    restarts = client.get("/api/status").json()["restarts"]
    running = idle_server.submit(random_field, SLOW).json()["id"]
    idle_server.wait_job(running, states=("running",))
    assert client.delete(f"/api/jobs/{running}").json() == {"id": running, "state": "cancelled"}
    job = client.get(f"/api/jobs/{running}").json()
    assert job["state"] == "cancelled" and job["error"] is None and job["finished"]
    assert client.get("/api/status").json()["restarts"] == restarts + 1  # its worker was killed


def test_queue_full_cancel_crash_and_time_limit_in_one_queue(idle_server, random_field, real_images):
    """One worker: a slow job runs while three wait (a fourth is 429). The waiting slow one is
    cancelled; the running one's worker is killed (the job fails, a new worker starts); the next
    job runs past its 1 s limit (killed, failed); the last one, a real image, is solved."""
    client = idle_server.client
    first = idle_server.submit(random_field, SLOW).json()["id"]
    idle_server.wait_job(first, states=("running",))
    limited = idle_server.submit(random_field, {**SLOW, "time_limit_s": 1}).json()["id"]
    real = idle_server.submit(real_images["roof.jpg"]).json()["id"]
    spare = idle_server.submit(random_field, SLOW).json()["id"]
    refused = idle_server.submit(random_field)
    assert refused.status_code == 429 and refused.headers["retry-after"] == "10"
    assert "the queue is full: 3 of 3 jobs waiting" in refused.json()["error"]
    assert client.get(f"/api/jobs/{spare}").json()["queue_position"] == 3
    unfinished = client.post("/api/analyses", json={"analysis": "radial", "sets": [{"jobs": [real]}]})
    assert unfinished.status_code == 409 and "is still queued" in unfinished.json()["error"]

    assert client.delete(f"/api/jobs/{spare}").json() == {"id": spare, "state": "cancelled"}
    [pid] = [w["pid"] for w in client.get("/api/status").json()["workers"] if w["job"] == first]
    os.kill(pid, signal.SIGKILL)
    crashed = idle_server.wait_job(first)
    assert crashed["state"] == "failed"
    assert crashed["error"] == "the worker process stopped unexpectedly (exit code -9); the server started a new one"
    assert pid not in idle_server.worker_pids()

    timed_out = idle_server.wait_job(limited)
    assert timed_out["state"] == "failed" and timed_out["error"] == "timed out after 1 s"
    assert timed_out["result"] is None and timed_out["stage"] in ("read", "detect", "identify")
    solved = idle_server.wait_job(real)
    assert solved["state"] == "done" and solved["result"]["n_matched"] >= 8
    assert client.get("/api/jobs/" + spare).json()["state"] == "cancelled"


def _left_behind(store: JobStore, source, state: str) -> str:
    """A job as a server that died would leave it (the store the server uses, its own calls)."""
    job_id, folder = store.reserve()
    shutil.copy(source, folder / "input.jpg")
    store.create("solve", {"label": source.name, "input": "input.jpg", "options":
                           validate_options({}, store.root.parent / "cameras"), "batch": None}, job_id)
    if state == "running":
        store.set_state(job_id, state="running", stage="identify", started="2026-01-01T00:00:00+00:00")
    return job_id


def test_a_restart_fails_the_job_left_running_and_queues_the_one_left_queued(tmp_path, real_images):
    data = tmp_path / "data"
    store = JobStore(data / "jobs")
    running = _left_behind(store, real_images["roof.jpg"], "running")
    queued = _left_behind(store, real_images["tree.jpg"], "queued")
    server = WebServer(data)
    try:
        job = server.client.get(f"/api/jobs/{running}").json()
        assert job["state"] == "failed" and job["error"] == RESTART_REASON
        listed = {j["id"]: j["state"] for j in server.client.get("/api/jobs").json()["jobs"]}
        assert set(listed) == {running, queued} and listed[queued] in ("queued", "running")  # queued again
    finally:
        server.stop()
    assert server.process.returncode == 0
