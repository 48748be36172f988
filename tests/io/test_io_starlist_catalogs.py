"""Star lists written by other programs: SExtractor's catalogs (ASCII_HEAD, FITS_LDAC) and
astrometry.net's xylists and corr files, whose positions are 1-based (startrack.io.read_star_list)."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.io import fits

from startrack.errors import InvalidInputError
from startrack.io import read_star_list, star_list_image_size

X0 = np.array([10.25, 300.5, 41.0])  # 0-based pixel centres (ours)
Y0 = np.array([20.5, 7.75, 199.0])
FLUX = np.array([900.0, 450.0, 120.0])

SEXTRACTOR_HEAD = """#   1 NUMBER                 Running object number
#   2 FLUX_APER              Flux vector within fixed circular aperture(s)              [count]
#   4 FLUX_AUTO              Flux within a Kron-like elliptical aperture                [count]
#   5 X_IMAGE                Object position along x                                    [pixel]
#   6 Y_IMAGE                Object position along y                                    [pixel]
"""


def _sextractor_rows() -> str:
    return "".join(f"{k + 1:10d} {f / 2:12.4f} {f / 3:12.4f} {f:12.4f} {x + 1:10.3f} {y + 1:10.3f}\n"
                   for k, (x, y, f) in enumerate(zip(X0, Y0, FLUX, strict=True)))


def _table(columns: dict[str, np.ndarray], name: str | None = None) -> fits.BinTableHDU:
    return fits.BinTableHDU.from_columns([fits.Column(name=k, format="E" if v.ndim == 1 else f"{v.shape[1]}E",
                                                      array=v) for k, v in columns.items()], name=name)


def test_a_sextractor_ascii_head_catalog_reads_with_its_1_based_positions_made_ours(tmp_path):
    path = tmp_path / "field.cat"
    path.write_text(SEXTRACTOR_HEAD + _sextractor_rows())
    stars = read_star_list(path)
    np.testing.assert_allclose(stars["x"], X0, atol=1e-9)  # pixels
    np.testing.assert_allclose(stars["y"], Y0, atol=1e-9)
    np.testing.assert_allclose(stars["flux"], FLUX, atol=1e-9)  # FLUX_AUTO, column 4 after the 2-vector FLUX_APER


def test_1_based_column_names_in_a_csv_are_made_ours_and_a_0_based_pair_wins(tmp_path):
    path = tmp_path / "stars.csv"
    path.write_text("X_IMAGE,Y_IMAGE,FLUX_AUTO\n11.25,21.5,300\n")
    assert {k: v.tolist() for k, v in read_star_list(path).items()} == {"x": [10.25], "y": [20.5], "flux": [300.0]}
    path.write_text("field_x,field_y,x,y\n11.25,21.5,3,4\n")
    assert read_star_list(path)["x"].tolist() == [3.0]
    path.write_text("x,Y_IMAGE\n1,2\n")  # one of each: neither pair is whole
    with pytest.raises(InvalidInputError, match=r"lacks required column.*'y'.*both 0-based or both 1-based"):
        read_star_list(path)
    path.write_text("X_IMAGE,FLUX_AUTO\n1,2\n")  # no y at all: nothing is mixed
    with pytest.raises(InvalidInputError, match=r"lacks required column.*or 1-based ywin_image, y_image, field_y\)$"):
        read_star_list(path)


def test_a_comment_that_starts_with_a_number_before_a_header_row_is_not_a_sextractor_header(tmp_path):
    path = tmp_path / "stars.csv"
    path.write_text("# 3 stars from the bench\nx,y\n1,2\n3,4\n5,6\n")
    assert read_star_list(path)["y"].tolist() == [2.0, 4.0, 6.0]


def test_an_astrometry_net_xylist_reads_with_its_1_based_positions_made_ours(tmp_path):
    """image2xy writes X, Y, FLUX, BACKGROUND, with 1,1 the centre of the first pixel (checked
    against Debian's astrometry.net 0.93: a star drawn at 0-based (50, 80) came out at X 51.0,
    Y 81.0)."""
    path = tmp_path / "field.xyls"
    table = _table({"X": X0 + 1, "Y": Y0 + 1, "FLUX": FLUX, "BACKGROUND": np.full(3, 100.0)})
    fits.HDUList([fits.PrimaryHDU(), table]).writeto(path)
    stars = read_star_list(path)
    np.testing.assert_allclose(stars["x"], X0, atol=1e-4)  # pixels (float32 columns)
    np.testing.assert_allclose(stars["y"], Y0, atol=1e-4)
    np.testing.assert_allclose(stars["flux"], FLUX, rtol=1e-6)


def test_a_fits_ldac_catalog_reads_from_its_objects_table_past_the_image_header_table(tmp_path):
    path = tmp_path / "field.ldac"
    imhead = fits.BinTableHDU.from_columns([fits.Column(name="Field Header Card", format="80A",
                                                        array=np.array(["SIMPLE  =                    T"]))],
                                           name="LDAC_IMHEAD")
    objects = _table({"XWIN_IMAGE": X0 + 1, "YWIN_IMAGE": Y0 + 1, "MAG_AUTO": np.array([5.0, 6.0, 7.5]),
                      "FLUX_APER": np.column_stack([FLUX, 2 * FLUX])}, name="LDAC_OBJECTS")
    fits.HDUList([fits.PrimaryHDU(), imhead, objects]).writeto(path)
    stars = read_star_list(path)
    assert set(stars) == {"x", "y", "flux", "mag"}
    np.testing.assert_allclose(stars["x"], X0, atol=1e-4)  # pixels
    np.testing.assert_allclose(stars["flux"], FLUX, rtol=1e-6)  # the first aperture of the vector column


@pytest.mark.parametrize(("hdus", "match"), [
    (lambda: [fits.PrimaryHDU(np.zeros((4, 4), np.float32))], r"holds no table \(an image is solved by solve_image"),
    (lambda: [fits.PrimaryHDU(), _table({"RA": np.ones(2), "DEC": np.ones(2)}, name="RADEC")],
     r"no FITS table with x and y positions.*RADEC: \['ra', 'dec'\]"),
    (lambda: [fits.PrimaryHDU(), _table({"X": np.array([1.0, np.nan]), "Y": np.ones(2)})],
     r"table row 2, column 'x'.*finite"),
    (lambda: [fits.PrimaryHDU(), fits.BinTableHDU.from_columns([
        fits.Column(name="X", format="5A", array=np.array(["a", "b"])),
        fits.Column(name="Y", format="E", array=Y0[:2])])],
     r"column\(s\) \['x'\] hold text, not numbers"),
])
def test_fits_tables_that_cannot_be_read_as_star_lists_say_why(tmp_path, hdus, match):
    path = tmp_path / "list.fits"
    fits.HDUList(hdus()).writeto(path)
    with pytest.raises(InvalidInputError, match=match):
        read_star_list(path)


def test_a_truncated_fits_file_is_refused_with_a_message(tmp_path):
    path = tmp_path / "list.fits"
    fits.HDUList([fits.PrimaryHDU(), _table({"X": X0, "Y": Y0})]).writeto(path)
    path.write_bytes(path.read_bytes()[:3000])
    with pytest.raises(InvalidInputError, match=r"star list .*list.fits"):
        read_star_list(path)


@pytest.mark.parametrize(("cards", "size"), [
    ({"IMAGEW": 640, "IMAGEH": 480}, (640, 480)),  # solve-field's .axy
    ({}, None),
    ({"IMAGEW": 640}, None),
    ({"IMAGEW": 0, "IMAGEH": 480}, None),
    ({"IMAGEW": 640.5, "IMAGEH": 480}, None),
    ({"IMAGEW": "wide", "IMAGEH": 480}, None),
])
def test_the_image_size_of_a_star_list_is_its_fits_headers_imagew_and_imageh(tmp_path, cards, size):
    primary = fits.PrimaryHDU()
    primary.header.update(cards)
    path = tmp_path / "field.axy"
    fits.HDUList([primary, _table({"X": X0 + 1, "Y": Y0 + 1})]).writeto(path)
    assert star_list_image_size(path) == size


def test_a_csv_or_a_missing_file_has_no_image_size(tmp_path):
    path = tmp_path / "stars.csv"
    path.write_text("x,y\n1,2\n")
    assert star_list_image_size(path) is None and star_list_image_size(tmp_path / "absent.axy") is None


def test_an_empty_fits_table_is_an_empty_list(tmp_path):
    path = tmp_path / "none.xyls"
    fits.HDUList([fits.PrimaryHDU(), _table({"X": np.zeros(0), "Y": np.zeros(0)})]).writeto(path)
    assert {k: v.shape for k, v in read_star_list(path).items()} == {"x": (0,), "y": (0,)}
