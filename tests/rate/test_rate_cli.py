"""``startrack rate`` on a streaked image and on an image pair."""

from __future__ import annotations

import json

import numpy as np
import pytest
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


def _pair_paths(tmp_path, omega, dt, count, seed):
    """Two images ``dt`` s apart of ``count`` point stars, the camera turning at ``omega`` (rad/s)."""
    rng = np.random.default_rng(seed)
    start = Rotation.random(random_state=rng)
    vectors = star_field(CAMERA, omega, dt, count, rng)
    flux = rng.uniform(2e4, 1e5, count)
    first = render_streak_scene(CAMERA, start, np.zeros(3), 0.01, vectors, flux, rng=rng)
    turned = propagate(Rotation.identity(), omega, dt).apply(vectors)
    second = render_streak_scene(CAMERA, start, np.zeros(3), 0.01, turned, flux, rng=rng)
    return [_write(tmp_path / "a.fits", first.image), _write(tmp_path / "b.fits", second.image)]


def test_stars_moving_most_of_their_spacing_give_the_right_rate(tmp_path, capsys):
    # 25 stars over 15 x 15 deg (~3 deg apart) moving 2.3 deg: nearest neighbours are other stars
    omega = np.array([3.0, -2.0, 2.0]) * DEG
    paths = _pair_paths(tmp_path, omega, 0.5, 25, 82)
    code = main(["rate", *paths, "--fov-deg", "15", "--dt-s", "0.5", "--max-motion-deg", "3", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "ok" and out["stars_matched"] >= 20
    error = np.array(out["omega_deg_s"]) * DEG - omega
    sigma = np.array(out["sigma_deg_s"]) * DEG
    assert np.all(np.abs(error) < 4 * sigma)
    assert np.linalg.norm(error) < 0.02 * np.linalg.norm(omega)  # rad/s: 2 % of the rate


def test_three_stars_are_too_few_for_a_pair_rate(tmp_path, capsys):
    paths = _pair_paths(tmp_path, np.array([0.002, -0.003, 0.004]), 0.5, 3, 83)
    assert main(["rate", *paths, "--fov-deg", "15", "--dt-s", "0.5", "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "too_few_stars" and out["omega_deg_s"] is None


@pytest.mark.parametrize(("count", "status"), [(8, "no_match"), (25, None)])
def test_a_motion_beyond_the_gate_says_to_raise_it(tmp_path, capsys, count, status):
    omega = np.array([3.0, -2.0, 2.0]) * DEG  # 2.3 deg in 0.5 s, gate 1 deg
    paths = _pair_paths(tmp_path, omega, 0.5, count, 82)
    assert main(["rate", *paths, "--fov-deg", "15", "--dt-s", "0.5", "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == (status or out["status"]) and out["omega_deg_s"] is None
    assert "raise --max-motion-deg" in out["reason"] and "non-parallel" not in out["reason"]
    if status == "no_match":
        assert out["reason"].startswith("no stars matched between the frames")


def test_rate_misuse_exits_2(tmp_path, capsys):
    path = _write(tmp_path / "x.fits", np.zeros((64, 64)))
    assert main(["rate", path, "--fov-deg", "15"]) == 2
    assert "--exposure-s" in capsys.readouterr().err
    assert main(["rate", path, path, "--fov-deg", "15"]) == 2
    assert main(["rate", path, "--exposure-s", "1"]) == 2  # no camera: argparse usage error
