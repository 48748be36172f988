"""Refusals of the io functions name the parameter and what is valid (InvalidInputError, a
ValueError). Before, each of these ended in an AttributeError or TypeError from deep inside, an
astropy or numpy message naming nothing of ours, or was accepted."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from startrack.camera import Camera
from startrack.errors import InvalidInputError
from startrack.io import read_image, read_star_list, write_fits, write_png
from startrack.io._truth_files import write_frame
from startrack.io._wcs import fit_sip, wcs_header, write_wcs

CAMERA = Camera.from_fov(64, 48, 10.0)
DISTORTED = CAMERA.with_distortion(k1=0.1)
IMAGE = np.zeros((4, 4), np.uint16)

CASES = {
    "output path None (was TypeError: expected str, bytes or os.PathLike)":
        (lambda tmp: write_png(None, IMAGE), "output path must be a file name"),
    "FITS header 3 (was AttributeError: 'int' object has no attribute 'items')":
        (lambda tmp: write_fits(tmp / "a.fits", IMAGE, header=3), "header must be a dict"),
    "FITS tables 3 (was AttributeError)":
        (lambda tmp: write_fits(tmp / "a.fits", IMAGE, tables=3), "tables must be a dict"),
    "WCS camera None (was AttributeError: 'NoneType' object has no attribute 'fx')":
        (lambda tmp: write_wcs(tmp / "a.wcs", Rotation.identity(), None), "camera must be a startrack.Camera"),
    "WCS date_obs garbage (was astropy's 'Input values did not match any of the formats')":
        (lambda tmp: wcs_header(Rotation.identity(), CAMERA, date_obs="garbage"), "date_obs must be an ISO 8601"),
    "SIP residual -1 px (was accepted)":
        (lambda tmp: wcs_header(Rotation.identity(), DISTORTED, max_residual_px=-1), "max_residual_px must be"),
    "SIP order 0 (was numpy's 'need at least one array to stack')":
        (lambda tmp: fit_sip(DISTORTED, order=0), "order must be None or a whole number from 2 to 13"),
    "SIP order 99 (was accepted)":
        (lambda tmp: fit_sip(DISTORTED, order=99), "order must be None or a whole number from 2 to 13"),
    "SIP order '2' (was TypeError: can only concatenate str)":
        (lambda tmp: fit_sip(DISTORTED, order="2"), "order must be None"),
    "star list path 3 (was TypeError from pathlib)":
        (lambda tmp: read_star_list(3), "path must be a file name"),
    "frame truth None (was AttributeError: no attribute 'rot_cam_from_icrs')":
        (lambda tmp: write_frame(tmp / "f.fits", IMAGE, None), "truth must be a startrack.simulate.Truth"),
    "max_pixels 0": (lambda tmp: read_image(IMAGE, max_pixels=0), "max_pixels must be a whole number"),
    "max_pixels 'many'": (lambda tmp: read_image(IMAGE, max_pixels="many"), "max_pixels must be a whole number"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_refusal_names_the_parameter(tmp_path, case):
    call, match = CASES[case]
    with pytest.raises(InvalidInputError, match=match):
        call(tmp_path)
    assert list(tmp_path.iterdir()) == []
