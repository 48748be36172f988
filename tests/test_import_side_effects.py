"""Importing startrack changes nothing outside it: every module (public and private) imports without setting
matplotlib's backend or importing pyplot, and without matplotlib at all (the ``plot`` extra), a
drawing function then says which extra to install (issue 21 item 4)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from startrack import AttitudeSolution, Detections, Status
from startrack.analysis._plots import plot_solution
from startrack.plotting import PLOT_EXTRA

SIDE_EFFECT_BY_DESIGN = {
    "startrack.__main__": "``python -m startrack``: its import runs the command line",
    "startrack.web._preload": "imported by the web worker pool's fork server to warm it: its import loads the "
                             "catalog and the pattern database and solves a star list (worker.prewarm)",
}
"""Modules whose import is meant to act, left out of the walk, each with the reason."""

IMPORT_EVERY_MODULE = f"""
import importlib, pkgutil, startrack
names = [m.name for m in pkgutil.walk_packages(startrack.__path__, "startrack.")
         if m.name not in {set(SIDE_EFFECT_BY_DESIGN)}]
for name in names:
    importlib.import_module(name)
print(len(names), "modules")
"""

DRAW_ONE_FIGURE = """
import numpy as np
import pytest
from startrack import AttitudeSolution, Detections, Status
from startrack.analysis._plots import plot_solution
from startrack.errors import StartrackError
try:
    plot_solution(np.zeros((8, 8)), Detections(), AttitudeSolution(Status.NO_MATCH, "test"), "unused.png")
except StartrackError as exc:
    print(type(exc).__name__, isinstance(exc, ImportError), "|", exc)
"""


WITH_SVG_BACKEND = ("import matplotlib, sys; matplotlib.use('svg')\n" + IMPORT_EVERY_MODULE
                    + "print(matplotlib.get_backend(), 'matplotlib.pyplot' in sys.modules)")
WITHOUT_MATPLOTLIB = "import sys; sys.modules['matplotlib'] = None\n" + IMPORT_EVERY_MODULE + DRAW_ONE_FIGURE


@pytest.fixture(scope="module")
def outputs() -> dict[str, list[str]]:
    """Standard output lines of the two fresh interpreters, run side by side (each imports ~300 modules)."""
    runs = {name: subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True)
            for name, code in (("svg", WITH_SVG_BACKEND), ("hidden", WITHOUT_MATPLOTLIB))}
    out = {}
    for name, run in runs.items():
        stdout, stderr = run.communicate(timeout=180)
        assert run.returncode == 0, stderr
        out[name] = stdout.strip().splitlines()
    return out


def test_every_module_keeps_the_backend_and_leaves_pyplot_unimported(outputs):
    assert int(outputs["svg"][0].split()[0]) > 100  # the walk found the package's modules, not an empty list
    assert outputs["svg"][1:] == ["svg False"]


def test_without_matplotlib_every_module_imports_and_drawing_names_the_extra(outputs):
    message = f"drawing a figure needs matplotlib, which is not installed: {PLOT_EXTRA}"
    assert outputs["hidden"] == [outputs["svg"][0], f"MissingExtraError True | {message}"]
    assert PLOT_EXTRA == "pip install 'startrack[plot]'"


def test_with_matplotlib_the_same_call_draws(tmp_path):
    path = tmp_path / "solution.png"
    plot_solution(np.zeros((8, 8)), Detections(), AttitudeSolution(Status.NO_MATCH, "test"), path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

