"""`startrack track FOLDER` on a short simulated sequence."""

import csv

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.attitude.propagation import propagate as propagate_attitude
from startrack.cli.main import main
from startrack.frames import attitude_error, random_rotations
from startrack.io import write_png
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import ARCSEC, DEG

CAMERA = Camera.from_fov(512, 512, 12.0)


def test_track_writes_one_row_per_frame_and_follows_the_truth(tmp_path, capsys):
    start = random_rotations(None, rng=21)
    rate = np.array([0.4, -0.8, 0.3]) * DEG
    truths = [propagate_attitude(start, rate, 0.1 * k) for k in range(6)]
    for k, truth in enumerate(truths):
        sim = simulate_frame(CAMERA, truth, max_mag=8.0, sensor=get_sensor_preset("generic-cmos"), rng=k)
        write_png(tmp_path / f"frame{k:03d}.png", sim.image)
    out = tmp_path / "track.csv"
    code = main(["track", str(tmp_path), "--fov-deg", "12", "--frame-interval-s", "0.1", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    with open(out, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["file"] for r in rows] == [f"frame{k:03d}.png" for k in range(6)]
    assert rows[0]["mode"] == "lost-in-space" and {r["mode"] for r in rows[2:]} == {"tracking"}
    for row, truth in zip(rows, truths, strict=True):
        quat = [float(row[k]) for k in ("qx", "qy", "qz", "qw")]
        assert attitude_error(truth, Rotation.from_quat(quat)) < 3 * CAMERA.pixel_scale_arcsec * ARCSEC
    assert abs(float(rows[-1]["rate_y_deg_s"]) - (-0.8)) < 0.05


def test_track_refuses_an_empty_folder(tmp_path, capsys):
    assert main(["track", str(tmp_path), "--fov-deg", "12"]) == 2
    err = capsys.readouterr().err
    assert "no image files" in err and err.count("\n") == 1
