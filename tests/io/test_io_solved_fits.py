"""Which header cards ``--new-fits`` writes again (startrack.io._solved_fits.carried_cards)."""

from __future__ import annotations

import numpy as np
from astropy.io import fits

from startrack.io import read_image, write_png
from startrack.io._solved_fits import carried_cards


def test_a_mosaic_read_into_one_plane_loses_its_bayer_cards_and_keeps_the_rest(tmp_path):
    cell = np.array([[300, 100], [100, 50]], dtype=np.uint16)
    header = fits.Header({"BAYERPAT": "RGGB", "XBAYROFF": 0, "EXPTIME": 30.0, "CRPIX1": 10.0, "CD1_1": 1e-3})
    path = tmp_path / "osc.fits"
    fits.PrimaryHDU(np.tile(cell, (20, 30)), header).writeto(path)
    image = read_image(path)
    assert image.mosaic == "RGGB"
    cards = carried_cards(image)
    assert cards["EXPTIME"] == 30.0
    for key in ("BAYERPAT", "XBAYROFF", "CRPIX1", "CD1_1"):
        assert key not in cards


def test_a_photo_carries_no_cards(tmp_path):
    path = tmp_path / "grey.png"
    write_png(path, np.zeros((20, 30), dtype=np.uint8))
    assert carried_cards(read_image(path)) == {}
