"""`startrack track FOLDER` on a short simulated sequence."""

import csv

import numpy as np
from scipy.spatial.transform import Rotation

from startrack import Camera
from startrack.attitude._propagation import propagate as propagate_attitude
from startrack.cli import main
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


def test_track_prints_the_smear_limits_and_the_mode_switches(tmp_path, capsys, slew_frames):
    for k, sim in enumerate(slew_frames):
        write_png(tmp_path / f"frame{k:03d}.png", sim.image)
    out = tmp_path / "track.csv"
    code = main(["track", str(tmp_path), "--fov-deg", "20", "--exposure-s", "0.1", "--frame-interval-s", "0.4",
                 "--out", str(out)])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    lines = printed.out.splitlines()
    # Samaan 2002 Table 1's rate for 0.1 px: 0.1 / fx / T, fx = 1452 px for 512 px over 20 deg
    assert lines[0].startswith("smear limit (Samaan 2002 Table 1): exposure 0.1 s") and "0.03946 deg/s" in lines[0]
    switches = [line for line in lines if " mode (smear " in line]
    assert len(switches) == 2 and "point -> streak mode" in switches[0] and "streak -> point mode" in switches[1]
    with open(out, newline="") as fh:
        modes = [row["mode"] for row in csv.DictReader(fh)]
    assert "streak tracking" in modes and modes[0] == "lost-in-space"


def test_track_refuses_a_bad_exposure(tmp_path, capsys):
    write_png(tmp_path / "frame000.png", np.zeros((64, 64), dtype=np.uint16))
    assert main(["track", str(tmp_path), "--fov-deg", "12", "--exposure-s", "-1"]) == 2
    assert "--exposure-s must be 0.0001 to 3600 s, got -1" in capsys.readouterr().err  # as startrack rate's
