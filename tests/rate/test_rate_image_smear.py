"""The smear a frame shows before there is a rate (rate._smear_mode.image_smear_px), which sets the
Tracker's mode for the first frame of a sequence.

Before: on a dense or small frame the 4 px bins of the streak candidates merged neighbouring
stars, so a still 512 x 512 px frame of 180 stars at 15 deg measured 28.5 px of smear; the Tracker
went to streak mode on its first frame, tried a streak solve (1.4 s) and only then the point
solve that found it, and `startrack track` said "point -> streak mode (smear 28.5 px)".
"""

from __future__ import annotations

import contextlib
import csv
import io
import math

import pytest

from startrack.cli import main
from startrack.io import read_image
from startrack.rate._smear_mode import image_smear_px
from startrack.units import PIXEL

EXPOSURE_S = 0.2  # the simulator's default sensor


def _simulate(path, size: int, rate_deg_s: tuple[float, float, float]) -> None:
    argv = ["simulate", "--fov-deg", "15", "--width", str(size), "--height", str(size), "--seed", "3",
            "--rate-deg-s", *map(str, rate_deg_s), "--out", str(path)]
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(argv) == 0


def _true_smear_px(size: int, rate_deg_s: tuple[float, float, float]) -> float:
    """The smear across the boresight (px) of a rate (deg/s) over the exposure."""
    return math.hypot(rate_deg_s[0], rate_deg_s[1]) * EXPOSURE_S * size / 15.0  # pinhole scale near the centre


@pytest.mark.parametrize(("size", "rate_deg_s", "tolerance_px"), [
    (512, (0.0, 0.0, 0.0), 4.0),     # still and dense: 28.5 px before
    (512, (0.3, 0.2, 0.0), 1.5),     # 2.4 px: 16.4 px before
    (1024, (1.0, 0.5, 0.0), 3.0),    # 15.3 px: streak mode, as before (14.4 px)
    (1024, (0.0, 0.0, 0.0), 4.0),
])
def test_the_smear_measured_in_the_image(tmp_path, size, rate_deg_s, tolerance_px):
    path = tmp_path / "frame.fits"
    _simulate(path, size, rate_deg_s)
    measured = image_smear_px(read_image(path).data)
    assert abs(measured - _true_smear_px(size, rate_deg_s)) < tolerance_px * PIXEL


def test_a_still_dense_sequence_is_tracked_in_point_mode_from_its_first_frame(tmp_path):
    folder = tmp_path / "seq"
    folder.mkdir()
    for k in range(2):
        _simulate(folder / f"frame_0000{k}.fits", 512, (0.0, 0.0, 0.0))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["track", str(folder), "--fov-deg", "15", "--out", str(tmp_path / "track.csv")])
    assert code == 0, err.getvalue()
    assert "streak mode (smear" not in out.getvalue() + err.getvalue()
    with open(tmp_path / "track.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["status"] for r in rows] == ["ok", "ok"] and rows[0]["mode"] == "lost-in-space"
