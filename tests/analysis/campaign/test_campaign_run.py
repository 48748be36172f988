"""Running campaigns on a local Dask cluster and synchronously: the trial table does not depend
on the number of workers or the chunking; resume, failures and lost workers; rerun."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time

import campaign_faulty_level  # noqa: F401  (registers "test-faulty"; workers import it from the spec)
import numpy as np
import pyarrow as pa
import pytest

from startrack.analysis.campaign._attitudes import trial_attitude
from startrack.analysis.campaign._rerun import rerun_trial
from startrack.analysis.campaign._run import run_campaign
from startrack.analysis.campaign._spec import parse_spec
from startrack.analysis.campaign._store import CampaignStore
from startrack.analysis.campaign._trials import trial_rng
from startrack.errors import InvalidInputError
from startrack.io import read_image

SPEC = """
[campaign]
name = "determinism"
level = "stars"
trials = 12
seed = 2026
[base]
max_mag = 6.0
false_stars = 2
drop_fraction = 0.1
[sweep]
fov_deg = [10.0, 20.0]
centroid_sigma_px = [0.1, 0.5]
"""
TIMES = ("time_s", "wall_s")


def assert_same_trials(a: pa.Table, b: pa.Table) -> None:
    """Equal tables but for the time columns (NaN equal to NaN)."""
    assert a.column_names == b.column_names
    assert a.num_rows == b.num_rows
    for name in a.column_names:
        if name in TIMES:
            continue
        x, y = a[name].to_pylist(), b[name].to_pylist()
        same = [u == v or (isinstance(u, float) and math.isnan(u) and math.isnan(v)) for u, v in zip(x, y, strict=True)]
        assert all(same), f"column {name} differs at rows {[i for i, s in enumerate(same) if not s][:5]}"


@pytest.fixture(scope="module")
def serial(tmp_path_factory) -> pa.Table:
    return run_campaign(SPEC, tmp_path_factory.mktemp("serial"), sync=True, chunk_size=5, report=False)


def test_one_and_two_workers_and_two_chunk_sizes_give_the_same_trials(serial, tmp_path):
    one = run_campaign(SPEC, tmp_path / "one", workers=1, chunk_size=7, report=False)
    two = run_campaign(SPEC, tmp_path / "two", workers=2, chunk_size=3, report=False)
    assert serial.num_rows == 48 and serial["status"].to_pylist().count("OK") > 40
    assert_same_trials(serial, one)
    assert_same_trials(serial, two)
    manifest = CampaignStore(tmp_path / "two").read_manifest()
    assert manifest["runs"][-1]["workers"] == 2 and manifest["chunk_size"] == 3
    assert manifest["catalog_hash"] and manifest["finished_utc"]


def test_resume_after_a_killed_run_gives_the_uninterrupted_table(serial, tmp_path):
    spec_path = tmp_path / "spec.toml"
    spec_path.write_text(SPEC)
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "startrack", "campaign", "run", str(spec_path), "--out", str(out),
           "--sync", "--chunk-size", "1", "--no-report"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    store = CampaignStore(out)
    deadline = time.monotonic() + 120
    while len(store.done_keys()) < 5 and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    done = len(store.done_keys())
    assert 5 <= done < 48, "the run must be cut off part-way"
    with pytest.raises(InvalidInputError, match="--resume"):
        run_campaign(spec_path, out, sync=True, report=False)
    resumed = run_campaign(spec_path, out, sync=True, resume=True, report=False)
    assert_same_trials(serial, resumed)
    assert len(CampaignStore(out).read_manifest()["runs"]) == 1   # the killed run never finished


def test_resume_refuses_another_spec(serial, tmp_path):
    run_campaign(SPEC, tmp_path, sync=True, report=False)
    with pytest.raises(InvalidInputError, match="another spec"):
        run_campaign(SPEC.replace("seed = 2026", "seed = 1"), tmp_path, sync=True, resume=True, report=False)


def _expected_failures(spec_text: str, cell: int) -> list[int]:
    """Trials of ``cell`` whose first draw after the attitude is below fail_fraction (0.3)."""
    spec = parse_spec(spec_text)
    out = []
    for k in range(spec.trials):
        rng = trial_rng(spec.seed, cell, k)
        trial_attitude(spec.attitudes, k, spec.trials, rng)
        if rng.random() < 0.3:
            out.append(k)
    return out


FAULTY = """
[campaign]
name = "faulty"
level = "test-faulty"
trials = 8
seed = 7
[base]
max_mag = 6.0
fail_fraction = 0.3
fault = "FAULT"
"""


def test_a_raising_trial_is_a_failure_row_on_dask(tmp_path):
    text = FAULTY.replace("FAULT", "raise")
    table = run_campaign(text, tmp_path, workers=2, chunk_size=3, report=False)
    failed = [r["trial"] for r in table.to_pylist() if r["status"] == "ERROR"]
    assert failed == _expected_failures(text, 0) and failed
    assert table.num_rows == 8


def test_a_worker_that_dies_costs_only_its_trial(tmp_path):
    text = FAULTY.replace("FAULT", "exit")
    table = run_campaign(text, tmp_path, workers=2, chunk_size=4, report=False)
    rows = table.to_pylist()
    lost = [r["trial"] for r in rows if r["status"] == "LOST"]
    assert lost == _expected_failures(text, 0) and lost
    assert all(r["status"] == "OK" for r in rows if r["trial"] not in lost)
    assert all(r["error"] for r in rows if r["status"] == "LOST")
    assert table.num_rows == 8


def test_trials_waiting_with_no_worker_left_become_lost_rows(tmp_path, monkeypatch):
    # A scheduler with no worker at all: the run ends with LOST rows (after NO_WORKERS_S), not a hang.
    from distributed import LocalCluster

    from startrack.analysis.campaign import _engine as engine

    monkeypatch.setattr(engine, "NO_WORKERS_S", 1.0)
    monkeypatch.setattr(engine, "POLL_S", 0.5)
    with LocalCluster(n_workers=0, processes=True, dashboard_address=":0", host="127.0.0.1") as cluster:
        t0 = time.perf_counter()
        table = run_campaign(FAULTY.replace("FAULT", "raise"), tmp_path, scheduler=cluster.scheduler_address,
                             chunk_size=4, report=False)
        waited_s = time.perf_counter() - t0
    rows = table.to_pylist()
    assert [r["trial"] for r in rows] == list(range(8)) and {r["status"] for r in rows} == {"LOST"}
    assert all("no Dask worker was connected for 1 s" in r["error"] for r in rows)
    assert waited_s < 60.0  # seconds: it gave up instead of waiting for a worker


IMAGE = """
[campaign]
name = "rerun"
level = "image"
trials = 2
seed = 11
[base]
width = 320
height = 256
fov_deg = 12.0
max_mag = 7.0
"""


def test_rerun_reproduces_a_trial_and_its_image_bit_for_bit(tmp_path):
    run_campaign(IMAGE, tmp_path / "out", sync=True, report=False)
    first = rerun_trial(tmp_path / "out", 0, 1, save_dir=tmp_path / "a")
    second = rerun_trial(tmp_path / "out", 0, 1, save_dir=tmp_path / "b")
    assert first.same is True and second.same is True
    assert first.row["status"] == "OK"
    a = read_image(first.files[0]).data
    b = read_image(second.files[0]).data
    assert a.shape == (256, 320) and np.array_equal(a, b)
    with pytest.raises(InvalidInputError, match="--trial must be in 0..1"):
        rerun_trial(tmp_path / "out", 0, 2)
    with pytest.raises(InvalidInputError, match="--cell must be in 0..0"):
        rerun_trial(tmp_path / "out", 3, 0)


def test_nothing_is_left_behind_when_a_run_cannot_start(tmp_path):
    with pytest.raises(InvalidInputError):
        run_campaign(SPEC, tmp_path / "x", scheduler="tcp://127.0.0.1:1", workers=2, report=False)
    assert not (tmp_path / "x" / "manifest.json").exists()


def test_a_refused_scheduler_or_chunk_size_leaves_no_folder(tmp_path, monkeypatch):
    """Before: --chunk-size 0 was checked after OUT/trials/ was made, and a scheduler that could
    not be reached left an empty OUT/."""
    from startrack.analysis.campaign import _engine as engine

    monkeypatch.setattr(engine, "CONNECT_S", 2.0)  # Dask retries a refused connection until then
    with pytest.raises(InvalidInputError, match="--chunk-size"):
        run_campaign(SPEC, tmp_path / "a", chunk_size=0, report=False)
    with pytest.raises(InvalidInputError, match="tcp://127.0.0.1:1"):
        run_campaign(SPEC, tmp_path / "b", scheduler="tcp://127.0.0.1:1", report=False)
    assert list(tmp_path.iterdir()) == []


def test_a_web_server_given_as_the_scheduler_is_refused_naming_it(tmp_path, monkeypatch):
    """The dashboard's port given by mistake: Dask read 'HTTP/1.1' as a frame length of exabytes
    (a MemoryError, worded as 'use a smaller image'), or, with a server that keeps the connection
    open without answering, waited past its own 20 s timeout."""
    import http.server
    import socket
    import threading

    from startrack.analysis.campaign import _engine as engine

    monkeypatch.setattr(engine, "CONNECT_S", 2.0)
    silent = socket.create_server(("127.0.0.1", 0))  # accepts, never answers
    class Quiet(http.server.BaseHTTPRequestHandler):
        def log_message(self, *args) -> None:  # the test's own output stays clean
            pass

    web = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    threading.Thread(target=web.serve_forever, daemon=True).start()
    try:
        for port in (web.server_address[1], silent.getsockname()[1]):
            t0 = time.perf_counter()
            with pytest.raises(InvalidInputError, match="no Dask scheduler answered") as info:
                run_campaign(SPEC, tmp_path / "out", scheduler=f"tcp://127.0.0.1:{port}", report=False)
            assert f"tcp://127.0.0.1:{port}" in str(info.value) and "dashboard" in str(info.value)
            assert time.perf_counter() - t0 < engine.CONNECT_S + 8.0  # s: the 2 s patched in, the 5 s margin, slack
            assert not (tmp_path / "out").exists()
    finally:
        web.shutdown()
        silent.close()


def test_a_scheduler_that_answers_after_the_wait_leaves_no_client_open(monkeypatch):
    """Before: the connection thread kept a Client that connected after the caller had given up."""
    import threading

    from startrack.analysis.campaign import _engine as engine

    monkeypatch.setattr(engine, "CONNECT_S", 0.1)
    closed, answer = threading.Event(), threading.Event()

    class Late:
        def __init__(self, address, timeout):
            answer.wait(60.0)  # s: connects only once the caller has given up (below)

        def close(self) -> None:
            closed.set()

    with pytest.raises(InvalidInputError, match="no Dask scheduler answered"):
        engine._scheduler_client(Late, "tcp://127.0.0.1:1")
    answer.set()
    assert closed.wait(timeout=10.0)  # s: the late client is closed as soon as it exists
