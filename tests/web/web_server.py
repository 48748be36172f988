"""A real ``startrack web`` server in a child process, for the HTTP and browser tests.

The server is started the way a user starts it (``python -m startrack web --port 0``;
no shell), on 127.0.0.1 with a port the system picks; the address is read from the line it
prints. Its standard error goes to a file (a pipe could fill and block it).
"""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx

STARTUP_S = 300.0
"""Limit of the server's start-up and of its worker's warm-up, s. With the tests' cache warm
(``tasks.py test`` warms it first) the worker is ready in seconds; from an empty cache, building
the database and compiling the kernels took 56 s on the idle 2-core reference machine, and more
than 90 s while the other test process ran."""
TERMINAL = ("done", "failed", "cancelled")


class WebServer:
    """``startrack web`` with ``args`` on ``data_dir``; ``client`` is an httpx client for it."""

    def __init__(self, data_dir: Path, *args: str):
        self.data_dir = Path(data_dir)
        self.data_dir.mkdir(parents=True, exist_ok=True)
        self.log = self.data_dir.parent / f"{self.data_dir.name}-server-{time.monotonic_ns()}.log"
        with open(self.log, "wb") as err:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "startrack", "web", "--port", "0", "--data-dir", str(self.data_dir),
                 *args], stdout=subprocess.DEVNULL, stderr=err, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.url = self._address()
        host, port = re.match(r"http://([\d.]+):(\d+)/", self.url).groups()
        self.host, self.port = host, int(port)
        self.client = httpx.Client(base_url=self.url, timeout=60.0)

    def _address(self) -> str:
        deadline = time.monotonic() + STARTUP_S
        while time.monotonic() < deadline:
            found = re.search(r"(http://[\d.]+:\d+/)", self.log.read_text(errors="replace"))
            if found:
                return found.group(1)
            if self.process.poll() is not None:
                raise RuntimeError(f"the server exited with {self.process.returncode}:\n{self.log.read_text()}")
            time.sleep(0.05)
        raise RuntimeError(f"the server printed no address in {STARTUP_S} s:\n{self.log.read_text()}")

    def wait_ready(self) -> dict:
        """Wait until every worker has loaded its catalog and database; returns /api/status."""
        deadline = time.monotonic() + STARTUP_S
        while time.monotonic() < deadline:
            status = self.client.get("/api/status").json()
            if not status["starting"] and all(w["ready"] for w in status["workers"]):
                return status
            time.sleep(0.1)
        raise RuntimeError(f"workers not ready after {STARTUP_S} s: {status}")

    def wait_job(self, job_id: str, states=TERMINAL, timeout_s: float = 60.0) -> dict:
        """Poll a job until its state is one of ``states``; returns its JSON."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            job = self.client.get(f"/api/jobs/{job_id}").json()
            if job["state"] in states:
                return job
            time.sleep(0.05)
        raise AssertionError(f"job {job_id} still {job['state']} after {timeout_s} s")

    def submit(self, path: Path, options: dict | None = None, name: str | None = None) -> httpx.Response:
        with open(path, "rb") as fh:
            data = {} if options is None else {"options": json.dumps(options)}
            return self.client.post("/api/jobs", files={"file": (name or path.name, fh)}, data=data)

    def worker_pids(self) -> list[int]:
        return [w["pid"] for w in self.client.get("/api/status").json()["workers"]]

    def raw_request(self, head: bytes, body_chunks=(), read_timeout_s: float = 30.0) -> tuple[int, dict]:
        """Send raw bytes (no client library in between: the body may be left unfinished) and
        return the status and JSON body of what the server answers."""
        with socket.create_connection((self.host, self.port), timeout=read_timeout_s) as sock:
            sock.sendall(head)
            for chunk in body_chunks:
                sock.sendall(chunk)
            answer = b""
            while True:
                head_end = answer.find(b"\r\n\r\n")
                if head_end >= 0:
                    length = re.search(rb"(?i)content-length: *(\d+)", answer[:head_end])
                    if length and len(answer) >= head_end + 4 + int(length.group(1)):
                        break
                part = sock.recv(65536)
                if not part:
                    break
                answer += part
        status = int(answer.split(b" ", 2)[1])
        return status, json.loads(answer[answer.find(b"\r\n\r\n") + 4:] or b"null")

    def stop(self) -> None:
        """Ctrl-C (the server stops its workers), then kill if it lingers."""
        self.client.close()
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(10)

    def kill(self) -> None:
        """SIGKILL the server process (a crash): nothing of it runs its shutdown."""
        self.client.close()
        self.process.kill()
        self.process.wait(10)
