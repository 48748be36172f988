"""startrack solve IMAGE --wcs OUT: a TAN-SIP WCS that astropy reads, close to astrometry.net's."""

from __future__ import annotations

import numpy as np
import pytest

from cli_runner import run
from startrack.io import write_png
from startrack.io._wcs import read_wcs


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


def test_new_fits_of_a_photo_holds_its_grey_plane_and_a_wcs_like_astrometry_nets(tmp_path, realdata_dir):
    from astropy.io import fits
    from astropy.wcs import WCS

    from startrack.io import read_image

    photo = realdata_dir / "smroid-cedar-solve" / "pleiades.jpg"
    out = tmp_path / "pleiades.new.fits"
    code, _, err = run("solve", photo, "--new-fits", out, "--fov-range-deg", 5, 35)
    assert code == 0, err
    with fits.open(out) as hdus:
        data, header = hdus[0].data, hdus[0].header
        np.testing.assert_array_equal(data, read_image(photo).data)  # R + G + B, as solved
        assert "DateTimeOriginal" not in header and header["CTYPE1"].startswith("RA---TAN")
        ours = WCS(header)
    truth = read_wcs(realdata_dir / "smroid-cedar-solve" / "truth" / "pleiades.wcs")
    x, y = _grid(truth)
    sep_px = ours.pixel_to_world(x, y).separation(truth.pixel_to_world(x, y)).arcsec / 71.65  # 71.65"/px
    assert np.max(sep_px) < 2.0


def test_new_fits_of_a_fits_file_keeps_its_cards_and_replaces_its_wcs(tmp_path):
    from astropy.io import fits
    from astropy.wcs import WCS

    simulated = tmp_path / "sim.fits"
    assert run("simulate", "--seed", 3, "--out", simulated)[0] == 0
    with fits.open(simulated) as hdus:
        data, header = hdus[0].data, hdus[0].header.copy()
    old = {"CTYPE1": "RA---TAN", "CRVAL1": 5.0, "CD1_1": 0.1, "PC1_2": 0.3, "CTYPE1A": "PIXEL", "A_ORDER": 2,
           "A_DMAX": 0.5, "CHECKSUM": "0000", "OBJECT": "a test field"}
    for key, value in old.items():
        header[key] = value
    header["HISTORY"] = "calibrated elsewhere"
    source = tmp_path / "with_old_wcs.fits"
    fits.PrimaryHDU(data, header).writeto(source)
    out, wcs_only = tmp_path / "new.fits", tmp_path / "new.wcs"
    code, _, err = run("solve", source, "--new-fits", out, "--wcs", wcs_only)
    assert code == 0, err
    with fits.open(out) as hdus:
        written, new = hdus[0].data, hdus[0].header
        np.testing.assert_array_equal(written, data)
        assert written.dtype == data.dtype
        assert new["OBJECT"] == "a test field" and new["TRUE_RA"] == header["TRUE_RA"]
        assert "calibrated elsewhere" in str(new["HISTORY"])
        for key in ("CTYPE1A", "PC1_2", "CHECKSUM", "A_DMAX"):
            assert key not in new
        ours = WCS(new)
    x, y = _grid(read_wcs(wcs_only))
    np.testing.assert_allclose(ours.pixel_to_world_values(x, y), read_wcs(wcs_only).pixel_to_world_values(x, y),
                               atol=1e-9)  # deg: the same WCS as --wcs writes


def test_new_fits_is_written_only_for_one_solved_image_and_never_over_it(tmp_path, realdata_dir):
    dark = tmp_path / "dark.png"
    write_png(dark, np.zeros((64, 64), dtype=np.uint8))
    out = tmp_path / "dark.fits"
    assert run("solve", dark, "--new-fits", out, "--fov-deg", 10)[0] == 1 and not out.exists()
    code, _, err = run("solve", dark, dark, "--new-fits", out)
    assert code == 2 and "--new-fits writes the image of one image; leave it out for a batch" in err
    photo = realdata_dir / "smroid-cedar-solve" / "pleiades.jpg"
    copy = tmp_path / "pleiades.jpg"
    copy.write_bytes(photo.read_bytes())
    code, _, err = run("solve", copy, "--new-fits", copy, "--fov-range-deg", 5, 35)
    assert code == 2 and copy.read_bytes() == photo.read_bytes()
