"""startrack solve IMAGE --wcs OUT: a TAN-SIP WCS that astropy reads, close to astrometry.net's."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest

from startrack.cli import main
from startrack.io import write_png
from startrack.io._wcs import read_wcs


def run(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def _grid(wcs, n=25):
    width, height = wcs.pixel_shape
    gx, gy = np.meshgrid(np.linspace(0, width - 1, n), np.linspace(0, height - 1, n))
    return gx.ravel(), gy.ravel()


def test_solve_writes_a_wcs_that_agrees_with_astrometry_net_across_the_frame(tmp_path, realdata_dir):
    out = tmp_path / "pleiades.wcs"
    code, stdout, err = run("solve", realdata_dir / "smroid-cedar-solve" / "pleiades.jpg", "--wcs", out,
                            "--fov-range-deg", 5, 35)
    assert code == 0, err
    ours, truth = read_wcs(out), read_wcs(realdata_dir / "smroid-cedar-solve" / "truth" / "pleiades.wcs")
    assert ours.pixel_shape == (512, 512)
    x, y = _grid(truth)
    sep_px = ours.pixel_to_world(x, y).separation(truth.pixel_to_world(x, y)).arcsec / 71.65
    assert np.sqrt(np.mean(sep_px**2)) < 1.0
    assert np.max(sep_px) < 2.0


def test_no_wcs_is_written_when_the_image_is_not_solved(tmp_path):
    image = tmp_path / "dark.png"
    write_png(image, np.zeros((64, 64), dtype=np.uint8))
    out = tmp_path / "dark.wcs"
    code, _, _ = run("solve", image, "--wcs", out, "--fov-deg", 10)
    assert code == 1
    assert not out.exists()


@pytest.mark.parametrize("bad", ["/nonexistent-folder/x.wcs"])
def test_an_unwritable_wcs_path_is_misuse(tmp_path, realdata_dir, bad):
    code, stdout, err = run("solve", realdata_dir / "smroid-cedar-solve" / "pleiades.jpg", "--wcs", bad,
                            "--fov-deg", 10.2)
    assert code == 2
    assert "does not exist" in err
