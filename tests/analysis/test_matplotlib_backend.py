"""Importing startrack's plotting modules leaves the user's matplotlib backend alone (three of them
switched it to Agg on import before, which changed a notebook user's backend)."""

from __future__ import annotations

import subprocess
import sys

MODULES = ("startrack.analysis.plots", "startrack.analysis.gallery", "startrack.analysis.calibration_plots",
           "startrack.analysis.postprocess", "startrack.analysis.campaign.figures", "startrack.cli.main")


def test_importing_the_plotting_modules_keeps_the_chosen_backend():
    code = ("import matplotlib; matplotlib.use('svg'); "
            + "; ".join(f"import {m}" for m in MODULES)
            + "; import sys; sys.modules.get('matplotlib.pyplot') is None or print('pyplot imported'); "
            "print(matplotlib.get_backend())")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    assert done.stdout.strip().splitlines() == ["svg"]
