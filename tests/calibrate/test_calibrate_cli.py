"""startrack calibrate: star images (joint calibration + one re-solve round) and checkerboards."""

import json

import numpy as np
import pytest

from cli_runner import run
from startrack.camera import Camera
from startrack.io import write_png

CEDAR_SAME_SIZE = ("crappy.jpg", "orion_trees.jpg", "roof.jpg")  # 507 x 507


def test_calibrate_from_three_real_images(tmp_path, realdata_dir):
    images = [realdata_dir / "smroid-cedar-solve" / name for name in CEDAR_SAME_SIZE]
    code, out, err = run("calibrate", *images, "--fov-range-deg", 5, 35, "--json", "--out", tmp_path / "cam.json")
    assert code == 0, err
    report = json.loads(out)
    assert report["status"] == "ok" and report["rms_px"] < 0.5
    assert all(item["status"] == "ok" and item["matches"] >= 20 for item in report["images"])
    camera = Camera(**json.loads((tmp_path / "cam.json").read_text()))
    assert camera.fov_deg == pytest.approx(10.2, abs=0.1)  # truth.csv: 10.19 deg
    assert camera.k1 < 0  # the lens has barrel distortion


def test_calibrate_from_checkerboard_pngs(tmp_path):
    pytest.importorskip("cv2")
    from scipy.spatial.transform import Rotation

    from startrack.calibrate._bench import Checkerboard, render_checkerboard

    board = Checkerboard(7, 5, 30.0)
    truth = Camera(width=400, height=300, fx=430.0, k1=-0.1)
    gen = np.random.default_rng(2)
    paths = []
    for k in range(8):
        rot = Rotation.from_euler("xyz", gen.uniform(-30, 30, 3), degrees=True)
        origin = np.array([gen.uniform(-40, 40), gen.uniform(-30, 30), 420.0]) - rot.apply([90.0, 60.0, 0.0])
        img = np.round(200 * render_checkerboard(truth, board, rot, origin, supersample=2) + 20).astype(np.uint8)
        paths.append(write_png(tmp_path / f"board{k}.png", img))
    code, out, err = run("calibrate", *paths, "--checkerboard", "7x5", "--square-mm", 30, "--json")
    assert code == 0, err
    report = json.loads(out)
    assert report["camera"]["fx"] == pytest.approx(430.0, rel=0.01)
    assert report["rms_px"] < 0.3


def test_bad_options_are_misuse(tmp_path, realdata_dir):
    image = realdata_dir / "smroid-cedar-solve" / "crappy.jpg"
    code, _, err = run("calibrate", image, "--fit", "f,focal")
    assert code == 2 and "--fit" in err
    code, _, err = run("calibrate", image, "--checkerboard", "nine-by-six")
    assert code == 2 and "--checkerboard" in err
