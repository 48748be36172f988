"""startrack calibrate's re-solve round: the reported camera, sigmas and pruned terms agree.

Before, the second round fitted from the first round's camera, in which cx, cy and aspect are
offsets from that camera: near zero, so always "pruned", while the first round's values stayed in
the camera without a sigma (and the other terms' sigmas were too small, those three being fixed)."""

from __future__ import annotations

import json

import pytest

from cli_runner import run
from startrack.camera import Camera
from startrack.cli._calibrate_cmd import PARAMETERS
from startrack.io._truth_files import write_frame
from startrack.simulate import get_sensor_preset, random_attitude, simulate_frame

DEFAULT_FIT = ("f", "aspect", "cx", "cy", "k1", "k2", "p1", "p2")
TRUTH = Camera(width=1024, height=768, fx=1911.0, fy=1925.0, cx=530.0, cy=370.0, k1=-0.1)
"""Principal point 18.5 px and 13.5 px off centre, pixels 0.7 % taller than wide, barrel distortion."""


def null_value(name: str, camera: dict) -> float:
    """The value of a pruned term in the reported camera: the pinhole's (centre, square pixels, zero)."""
    return {"aspect": camera["fx"], "cx": (camera["width"] - 1) / 2,
            "cy": (camera["height"] - 1) / 2}.get(name, 0.0)


def value(name: str, camera: dict) -> float:
    return camera["fy"] if name == "aspect" else camera[name]


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> dict:
    path = tmp_path_factory.mktemp("cal") / "star.fits"
    sensor = get_sensor_preset("generic-cmos").with_exposure(0.2)
    sim = simulate_frame(TRUTH, random_attitude(100), sensor=sensor, max_mag=7.0, rng=0)  # 187 stars
    write_frame(path, sim.image, sim.truth)
    code, out, err = run("calibrate", path, "--fov-deg", 30, "--json")
    assert code == 0, err
    return json.loads(out)


def test_every_fitted_term_is_either_free_with_a_sigma_or_pruned_at_its_null_value(report):
    camera, sigma, pruned = report["camera"], report["sigma"], report["pruned"]
    assert set(sigma) | set(pruned) == set(DEFAULT_FIT) and not set(sigma) & set(pruned)
    for name in pruned:
        assert value(name, camera) == pytest.approx(null_value(name, camera), abs=1e-12), name  # exact (px or 1)
    for name in set(PARAMETERS) - set(DEFAULT_FIT):
        assert camera[name] == 0.0, name


def test_the_principal_point_and_aspect_are_recovered_with_their_sigmas(report):
    camera, sigma = report["camera"], report["sigma"]
    assert {"aspect", "cx", "cy", "k1"} <= set(sigma)  # was: aspect, cx and cy "pruned"
    assert camera["cx"] == pytest.approx(TRUTH.cx, abs=max(4 * sigma["cx"], 0.1))  # px; sigma ~0.2 px
    assert camera["cy"] == pytest.approx(TRUTH.cy, abs=max(4 * sigma["cy"], 0.1))  # px; sigma ~0.2 px
    assert camera["fy"] / camera["fx"] == pytest.approx(TRUTH.fy / TRUTH.fx, abs=1e-4)  # ratio; sigma ~2e-5
    assert sigma["cx"] < 1.0 and sigma["cy"] < 1.0  # px
    assert camera["k1"] == pytest.approx(TRUTH.k1, abs=2e-3)  # dimensionless; sigma ~4e-4


def test_an_image_given_twice_is_refused(tmp_path, monkeypatch):
    """Before: its stars counted twice and every sigma came out too small by sqrt(2)."""
    image = tmp_path / "a.fits"
    image.write_bytes(b"")
    monkeypatch.chdir(tmp_path)
    code, out, err = run("calibrate", str(image), "a.fits")
    assert code == 2 and out == "" and "a.fits is given twice" in err, err
