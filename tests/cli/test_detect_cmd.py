"""``startrack detect IMAGE``: the table, the JSON records, the options, bad input."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from startrack.cli import main
from startrack.io import write_png
from startrack.simulate import render_gaussian_psf
from startrack.units import PIXEL

STARS_X, STARS_Y = np.array([30.4, 80.7, 120.2]), np.array([40.6, 90.1, 20.9])
FLUX = np.array([3e4, 1e4, 5e3])


def _run(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def png(tmp_path_factory):
    rng = np.random.default_rng(1)
    image = render_gaussian_psf((128, 160), STARS_X, STARS_Y, FLUX, 1.3) + 100.0
    image += rng.normal(0.0, 3.0, image.shape)
    path = tmp_path_factory.mktemp("detect") / "stars.png"
    write_png(path, np.clip(np.rint(image), 0, 65535).astype(np.uint16))
    return path


def test_table_lists_the_stars_brightest_first(png):
    code, out, err = _run("detect", png)
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].startswith("3 stars in 160 x 128 px")
    rows = np.array([line.split()[:3] for line in lines[2:]], dtype=float)
    np.testing.assert_allclose(rows[:, 0], STARS_X, atol=0.05 * PIXEL)
    np.testing.assert_allclose(rows[:, 1], STARS_Y, atol=0.05 * PIXEL)


@pytest.mark.parametrize("method", ["weighted", "mle", "peak"])
def test_json_records_with_a_method(png, method):
    code, out, _ = _run("detect", png, "--json", "--method", method, "--max-stars", 2)
    assert code == 0
    data = json.loads(out)
    assert data["centroid"] == method and data["width"] == 160 and len(data["stars"]) == 2
    star = data["stars"][0]
    assert {"x", "y", "flux", "sigma_px", "mag", "peak_snr", "area_px", "major_px"} <= set(star)
    assert star["x"] == pytest.approx(STARS_X[0], abs=0.6 * PIXEL)
    assert data["settings"]["centroid"] == method


def test_dark_frame_and_threshold_options(png, tmp_path):
    dark = tmp_path / "dark.png"
    write_png(dark, np.full((128, 160), 100, dtype=np.uint16))
    code, out, _ = _run("detect", png, "--dark", dark, "--threshold", "dynamic", "--json")
    assert code == 0 and len(json.loads(out)["stars"]) == 3


def test_bad_input_exits_2(tmp_path, png):
    code, out, err = _run("detect", tmp_path / "missing.png")
    assert code == 2 and out == "" and err.startswith("startrack detect: error:")
    code, _, err = _run("detect", png, "--method", "centre")
    assert code == 2 and "invalid choice" in err
    wrong = tmp_path / "wrong.png"
    write_png(wrong, np.zeros((10, 10), dtype=np.uint16))
    code, _, err = _run("detect", png, "--dark", wrong)
    assert code == 2 and "a dark frame must have the image's size" in err
