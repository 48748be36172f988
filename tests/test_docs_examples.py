"""The code examples of docs/*.md run (issue 21 item 6): every ```python block is executed, after
the setup that gives its placeholders real values (``SETUP``), in a temporary working folder;
those that need the network, real-image folders, or runs of minutes are skipped with the reason
(``SKIPPED``). A block added to the docs runs as it is until it is listed here."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
BLOCK = re.compile(r"^```python\n(.*?)^```", flags=re.S | re.M)

SIMULATED_FRAME = """
from startrack import Camera
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.frames import rotation_from_radec_roll
from startrack.units import DEG
_camera = Camera.from_fov(640, 480, 12.0)
_sim = simulate_frame(_camera, rotation_from_radec_roll(83.8 * DEG, -1.0 * DEG, 0.0), max_mag=6.5,
                      sensor=get_sensor_preset("generic-cmos").with_exposure(0.2), rng=5)
image = _sim.image
"""

SETUP = {
    "attitude_and_rate.md#0": """
import numpy as np
from scipy.spatial.transform import Rotation
reference = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.6, 0.8, 0.0]])
observed = Rotation.from_euler("xyz", [10, -20, 30], degrees=True).apply(reference)
""",
    "conventions.md#0": """
import numpy as np
from scipy.spatial.transform import Rotation
rot_cam_from_icrs = Rotation.from_euler("zyx", [40, 10, -5], degrees=True)
v_icrs = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
""",
    "conventions.md#1": """
from scipy.spatial.transform import Rotation
rot_cam_from_body = Rotation.from_euler("x", 90, degrees=True)
rot_body_from_icrs = Rotation.from_euler("zyx", [40, 10, -5], degrees=True)
""",
    "conventions.md#2": """
from scipy.spatial.transform import Rotation
truth = Rotation.from_euler("zyx", [40, 10, -5], degrees=True)
estimate = Rotation.from_rotvec([1e-5, 0.0, 0.0]) * truth
""",
    "conventions.md#4": """
from scipy.spatial.transform import Rotation
qx, qy, qz, qw = 0.0, 0.0, 0.38268343, 0.92387953
""",
    "conventions.md#5": "angle_rad = 2.5e-5",
    "detection.md#0": SIMULATED_FRAME + """
import numpy as np
dark = np.zeros_like(image)
x_pred, y_pred = _sim.truth.x[:5], _sim.truth.y[:5]
""",
    "tracking.md#0": """
import numpy as np
from startrack import Camera
from startrack.catalog import load_catalog
from startrack.frames import radec_to_vector, rotation_from_radec_roll
from startrack.units import DEG
_camera, _catalog = Camera.from_fov(1024, 1024, 15.0), load_catalog()
_bright = _catalog.v_mag < 6.5
_stars = radec_to_vector(_catalog.ra_rad[_bright], _catalog.dec_rad[_bright])
frames = []
for _k in range(3):  # the camera turning 0.1 deg/s in RA, a frame every 0.5 s: star lists, brightest first
    _v = rotation_from_radec_roll((83.8 + 0.05 * _k) * DEG, -1.0 * DEG, 0.0).apply(_stars)
    _x, _y = _camera.vector_to_pixel(np.where(_v[:, 2:] > 0.5, _v, [0.0, 0.0, 1.0]))
    _seen = np.flatnonzero((_v[:, 2] > 0.5) & _camera.in_image(_x, _y))
    _seen = _seen[np.argsort(_catalog.v_mag[_bright][_seen], kind="stable")]
    frames.append((0.5 * _k, (_x[_seen], _y[_seen])))
""",
}
"""Block id ("page.md#k", the k-th ```python block of the page) -> code run before it."""

SKIPPED = {
    "adcs.md#0": "a 700 s closed-loop run (about 200 s of wall time)",
    "analysis.md#0": "needs a folder of night-sky images (night/)",
    "attitude_and_rate.md#1": "a fragment: needs a streaked image, its camera and a rough rate",
    "calibration.md#0": "needs real sky images (paths) and solves each with a FOV search (minutes)",
    "campaign_report.md#0": "needs a finished campaign in out/fov-noise (minutes of Dask trials)",
    "campaign_report.md#1": "registers a report section in the running process (every later report would carry it)",
    "web.md#0": "needs a running web server at 127.0.0.1:8000",
}
"""Block id -> why it does not run in the test suite."""


def blocks() -> dict[str, str]:
    """Every ```python block of docs/*.md by its id ("page.md#k")."""
    out = {}
    for page in sorted(DOCS.glob("*.md")):
        for k, match in enumerate(BLOCK.finditer(page.read_text())):
            out[f"{page.name}#{k}"] = match.group(1)
    return out


BLOCKS = blocks()


def test_the_lists_name_existing_blocks():
    assert not (set(SETUP) | set(SKIPPED)) - set(BLOCKS)  # a moved or deleted block: update the lists
    assert not set(SETUP) & set(SKIPPED)
    assert len(BLOCKS) >= 15


@pytest.mark.parametrize("block_id", [b for b in BLOCKS if b not in SKIPPED])
def test_example_runs(block_id, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples that write files (rig.json) write them here
    namespace: dict = {"__name__": "docs_example"}
    exec(compile(SETUP.get(block_id, ""), f"<setup of {block_id}>", "exec"), namespace)
    exec(compile(BLOCKS[block_id], f"docs/{block_id}", "exec"), namespace)


@pytest.mark.parametrize("block_id", sorted(SKIPPED))
def test_skipped_example_compiles(block_id):
    compile(BLOCKS[block_id], f"docs/{block_id}", "exec")  # at least its syntax is right
    pytest.skip(SKIPPED[block_id])
