"""Interoperability of simulated FITS frames (docs/io.md, "Interoperability"): astropy, DS9 and
astrometry.net's solve-field read them as an image with its truth alongside.

solve-field decides between "image" and "star list" by opening extension 1 as a table and asking
for columns X and Y, matched without regard to case (``xylist_is_file_xylist`` in astrometry.net's
``util/xylist.c``, ``fits_find_column`` with ``strcasecmp``); our TRUTH table has columns x and y,
so it must not be extension 1. :func:`_taken_for_a_star_list` states that rule; when solve-field
is installed it is also run (``--just-augment``: source extraction, no index files needed).
"""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from astropy.io import fits

from startrack.camera import Camera
from startrack.frames import rotation_from_radec_roll
from startrack.io import read_image
from startrack.io._truth_files import TRUTH_NOTE_EXTNAME, write_frame
from startrack.simulate import get_sensor_preset, simulate_frame
from startrack.units import DEG


@pytest.fixture(scope="module")
def frame(tmp_path_factory):
    camera = Camera.from_fov(256, 256, 15.0)
    sim = simulate_frame(camera, rotation_from_radec_roll(80 * DEG, 20 * DEG, 0.0), max_mag=7.5, rng=4,
                         sensor=get_sensor_preset("generic-cmos"))
    path = tmp_path_factory.mktemp("interop") / "frame.fits"
    write_frame(path, sim.image, sim.truth)
    return path, sim


def _taken_for_a_star_list(path) -> bool:
    """astrometry.net's rule: extension 1 is a table with columns X and Y (any case)."""
    with fits.open(path) as hdus:
        if len(hdus) < 2 or not isinstance(hdus[1], fits.BinTableHDU | fits.TableHDU):
            return False
        return {"X", "Y"} <= {name.upper() for name in hdus[1].columns.names}


def test_a_simulated_fits_is_an_image_to_astrometry_net(frame):
    """Before: the TRUTH table was extension 1 and solve-field refused the file ('image width and
    height must be specified for XYLS inputs')."""
    path, _ = frame
    assert not _taken_for_a_star_list(path)


def test_astropy_reads_the_image_first_and_the_truth_by_name(frame):
    path, sim = frame
    with fits.open(path) as hdus:
        assert hdus[0].data.shape == (256, 256) and hdus[0].header["CTYPE1"] == "RA---TAN"
        assert hdus[1].name == TRUTH_NOTE_EXTNAME and hdus[1].data is None
        table = hdus["TRUTH"].data
        np.testing.assert_allclose(table["x"], sim.truth.x[sim.truth.inside()])
    np.testing.assert_array_equal(fits.getdata(path), sim.image)
    np.testing.assert_array_equal(read_image(path).data, sim.image)


@pytest.mark.skipif(shutil.which("solve-field") is None, reason="astrometry.net's solve-field is not installed")
def test_solve_field_extracts_sources_from_a_simulated_fits(frame, tmp_path):
    path, _ = frame
    proc = subprocess.run(["solve-field", "--just-augment", "--no-plots", "--overwrite", "--dir", str(tmp_path),
                           str(path)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "XYLS" not in proc.stdout + proc.stderr and "simplexy: found" in proc.stdout
    assert (tmp_path / "frame.axy").is_file()
