"""Fixtures of the browser tool's tests: a real server (child process) shared by the session, the
real images it is given, a ``--root`` folder for folder mode, and a slow job's image."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from web_server import WebServer

from startrack.io import write_png

MAX_UPLOAD_MB = 8
MAX_QUEUED = 3
SLOW = {"method": "pyramid", "fov_deg": 10.0}
"""Options that make the random field a job of at least 5 s: the pyramid matcher tries pairs of a
field that matches no sky until its own 5 s limit."""


@pytest.fixture(scope="session")
def real_images(realdata_dir: Path) -> dict[str, Path]:
    """name -> path of every real image with an astrometry.net solution (skips when absent)."""
    return {p.name: p for p in sorted(realdata_dir.glob("*/*")) if p.suffix in (".jpg", ".png")
            and p.name != "median_image.png"}


@pytest.fixture(scope="session")
def random_field(tmp_path_factory) -> Path:
    """A 512 x 512 frame of 60 star-like spots at random places: no sky looks like it, so the
    lost-in-space search finds nothing; with :data:`SLOW` it searches for 5 s - a real slow job."""
    rng = np.random.default_rng(1)
    yy, xx = np.mgrid[0:512, 0:512]
    image = rng.normal(100.0, 3.0, (512, 512))
    for x, y, amplitude in zip(rng.uniform(10, 502, 60), rng.uniform(10, 502, 60), rng.uniform(200, 3000, 60),
                               strict=True):
        image += amplitude * np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * 1.2**2))
    path = tmp_path_factory.mktemp("random") / "random_field.png"
    write_png(path, np.clip(image, 0, 65535).astype(np.uint16))
    return path


@pytest.fixture(scope="session")
def web_root(tmp_path_factory, real_images) -> Path:
    """The ``--root`` folder: ``night/`` with two real images, ``empty/``, and in ``night/`` a
    link to a file outside the root (which folder mode must skip)."""
    root = tmp_path_factory.mktemp("root")
    night = root / "night"
    night.mkdir()
    for name in ("roof.jpg", "tree.jpg"):
        (night / name).write_bytes(real_images[name].read_bytes())
    outside = tmp_path_factory.mktemp("outside") / "secret.png"
    outside.write_bytes(real_images["crappy.jpg"].read_bytes())
    os.symlink(outside, night / "zz_link_out.png")
    (root / "empty").mkdir()
    os.symlink(outside.parent, root / "link_dir")
    return root


IN_PROCESS = ("test_uploads.py",)
"""Test files that need no server: they run first, while the session's server warms up."""


def pytest_collection_modifyitems(items):
    items.sort(key=lambda item: item.path.name not in IN_PROCESS)  # stable: the order within each kept


@pytest.fixture(scope="session")
def started_server(tmp_path_factory, web_root):
    """The session's server process, started (not yet warm): 1 worker, 8 MB uploads, 3 queued
    jobs at most, folder mode under :func:`web_root`."""
    data = tmp_path_factory.mktemp("web") / "data"
    srv = WebServer(data, "--max-upload-mb", str(MAX_UPLOAD_MB), "--max-queued", str(MAX_QUEUED),
                    "--root", str(web_root), "--time-limit-s", "60")
    try:
        yield srv
    finally:
        srv.stop()


@pytest.fixture(scope="session", autouse=True)
def _start_the_server_early(request):
    """Start the session's server at the beginning (if any test of the session uses it), so that
    its worker warms up while the in-process tests run."""
    if any("server" in item.fixturenames or "idle_server" in item.fixturenames for item in request.session.items):
        request.getfixturevalue("started_server")


@pytest.fixture(scope="session")
def server(started_server) -> WebServer:
    """The session's server with its worker ready."""
    started_server.wait_ready()
    return started_server


@pytest.fixture()
def idle_server(server) -> WebServer:
    """The session server with no job waiting or running (earlier tests' jobs cancelled) and its
    worker ready."""
    for job in server.client.get("/api/jobs").json()["jobs"]:
        if job["state"] in ("queued", "running"):
            server.client.delete(f"/api/jobs/{job['id']}")
    server.wait_ready()
    return server
