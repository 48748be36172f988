"""``startrack rate`` on a streaked image and on an image pair."""

from __future__ import annotations

import json

import numpy as np
from scipy.spatial.transform import Rotation
from streak_scenes import render_streak_scene, spin_rate, star_field

from startrack.attitude import propagate
from startrack.camera import Camera
from startrack.cli import main
from startrack.io import write_fits
from startrack.units import DEG

CAMERA = Camera.from_fov(512, 512, fov_deg=15.0)


def _write(path, image):
    write_fits(path, np.clip(np.round(image), 0, 65535).astype(np.uint16))
    return str(path)


def test_rate_of_a_streaked_image(tmp_path, capsys):
    rng = np.random.default_rng(80)
    omega = spin_rate(70 * DEG, 0.05, 0.4)
    exposure = 0.2 * 15 * DEG / 0.05
    scene = render_streak_scene(CAMERA, Rotation.random(random_state=rng), omega, exposure,
                                star_field(CAMERA, omega, exposure, 6, rng), rng.uniform(1e5, 3e5, 6), rng=rng)
    path = _write(tmp_path / "streaks.fits", scene.image)
    prior = [f"{v:.3f}" for v in omega / DEG]
    code = main(["rate", path, "--fov-deg", "15", "--exposure-s", str(exposure), "--bias-px", "0.64", "--json",
                 "--prior-rate-deg-s", *prior])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "ok" and out["time_order_known"]
    np.testing.assert_allclose(np.array(out["omega_deg_s"]) * DEG, omega, atol=0.01 * 0.05)


def test_rate_of_an_image_pair(tmp_path, capsys):
    rng = np.random.default_rng(81)
    omega = np.array([0.002, -0.003, 0.004])
    start = Rotation.random(random_state=rng)
    vectors = star_field(CAMERA, omega, 0.5, 25, rng)
    flux = rng.uniform(2e4, 1e5, 25)
    first = render_streak_scene(CAMERA, start, np.zeros(3), 0.01, vectors, flux, rng=rng)
    turned = propagate(Rotation.identity(), omega, 0.5).apply(vectors)
    second = render_streak_scene(CAMERA, start, np.zeros(3), 0.01, turned, flux, rng=rng)
    paths = [_write(tmp_path / "a.fits", first.image), _write(tmp_path / "b.fits", second.image)]
    assert main(["rate", *paths, "--fov-deg", "15", "--dt-s", "0.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["stars_matched"] >= 20
    np.testing.assert_allclose(np.array(out["omega_deg_s"]) * DEG, omega, atol=0.03 * np.linalg.norm(omega))


def test_rate_misuse_exits_2(tmp_path, capsys):
    path = _write(tmp_path / "x.fits", np.zeros((64, 64)))
    assert main(["rate", path, "--fov-deg", "15"]) == 2
    assert "--exposure-s" in capsys.readouterr().err
    assert main(["rate", path, path, "--fov-deg", "15"]) == 2
    assert main(["rate", path, "--exposure-s", "1"]) == 2  # no camera: argparse usage error
