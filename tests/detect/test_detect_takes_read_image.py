"""detect takes what read_image returns, and an astropy HDU, for their pixels. Before, both
gave "image must hold integers or floats, got dtype object"."""

from __future__ import annotations

import numpy as np
from astropy.io import fits

from startrack.detect import detect
from startrack.io import read_image, write_fits
from startrack.simulate import render_gaussian_psf


def test_an_image_read_from_a_file_is_detected_as_its_pixels(tmp_path):
    rng = np.random.default_rng(1)
    x, y = rng.uniform(20, 230, 8), rng.uniform(20, 230, 8)
    pixels = rng.poisson(render_gaussian_psf((256, 256), x, y, np.full(8, 5e3), 1.3) + 50.0).astype(np.uint16)
    path = tmp_path / "frame.fits"
    write_fits(path, pixels)
    expected = detect(pixels)
    assert len(expected) == 8
    with fits.open(path) as hdus:
        for source in (read_image(path), hdus[0]):
            found = detect(source)
            np.testing.assert_array_equal(found.x, expected.x)
            np.testing.assert_array_equal(found.y, expected.y)
