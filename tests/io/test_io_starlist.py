"""CSV star lists (startrack.io.read_star_list)."""

from __future__ import annotations

import numpy as np
import pytest

from startrack.errors import InvalidInputError
from startrack.io import read_star_list


def _write(tmp_path, text):
    path = tmp_path / "stars.csv"
    path.write_text(text)
    return path


def test_reads_required_and_optional_columns(tmp_path):
    text = "# measured\n X , y,Flux,mag,id\n1.5,2.25,100,5.1,a\n-0.5,3,2e3,4.2,b\n"
    path = _write(tmp_path, text)
    stars = read_star_list(path)
    assert set(stars) == {"x", "y", "flux", "mag"}
    np.testing.assert_array_equal(stars["x"], [1.5, -0.5])
    np.testing.assert_array_equal(stars["y"], [2.25, 3.0])
    np.testing.assert_array_equal(stars["flux"], [100.0, 2000.0])
    assert stars["x"].dtype == np.float64


def test_header_only_gives_empty_arrays(tmp_path):
    stars = read_star_list(_write(tmp_path, "x,y\n"))
    assert stars["x"].shape == (0,) and set(stars) == {"x", "y"}


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("x,flux\n1,2\n", r"lacks required column.*'y'"),
        ("x,y\n1,nan\n", r"line 2, column 'y'.*finite"),
        ("x,y\n1,2\n3,inf\n", r"line 3, column 'y'.*finite"),
        ("x,y\n1,two\n", r"line 2, column 'y'.*'two' is not a number"),
        ("x,y\n1,1_000\n", r"line 2, column 'y'.*'1_000' is not a number"),
        ("x,y\n1,\n", r"line 2, column 'y'.*is not a number"),
        ("x,y\n1,2,3\n", r"line 2: 3 fields, expected 2"),
        ("x,x,y\n1,2,3\n", r"duplicate column"),
        ("", r"empty"),
        ("# only a comment\n", r"empty"),
    ],
)
def test_bad_lists_name_file_and_problem(tmp_path, text, match):
    path = _write(tmp_path, text)
    with pytest.raises(InvalidInputError, match=match) as info:
        read_star_list(path)
    assert "stars.csv" in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(InvalidInputError, match="does not exist"):
        read_star_list(tmp_path / "nope.csv")


@pytest.mark.parametrize("text", [
    "x\ty\tflux\n1.5\t2.25\t100\n-0.5\t3\t2000\n",  # tab-separated
    "x;y;flux\n1,5;2,25;100\n-0,5;3;2000\n",  # a spreadsheet's semicolons and decimal commas
    "x y  flux\n 1.5   2.25 100\n-0.5 3 2000\n",  # blanks
    "# x y flux\n1.5 2.25 100\n-0.5 3 2000\n",  # the header written as a comment
    "x_px,y_px,intensity # pixels\n1.5,2.25,100\n-0.5,3,2e3 # a note\n",  # a unit in the names, comments after
    "id,xcentroid,ycentroid,flux,sharpness\n1,1.5,2.25,100,0.5\n2,-0.5,3,2000,0.6\n",  # photutils' names
    "col,row,counts\r\n1.5,2.25,100\r\n-0.5,3,2000\r\n",  # a pixel grid's names, Windows line ends
    "# x;y;flux\n1,5;2,25;100\n-0,5;3;2000\n",  # a commented header, semicolons and decimal commas
    'x,y,name,flux\n1.5,2.25,"HIP #5",100\n-0.5,3,"Vega",2000\n',  # a quoted '#' is no comment
])
def test_the_csv_forms_people_write_read_the_same(tmp_path, text):
    """Before: each of these was refused (a separator other than a comma, other column names) or,
    for a comment after the header's names, lost its flux column without a word."""
    stars = read_star_list(_write(tmp_path, text))
    assert set(stars) == {"x", "y", "flux"}
    np.testing.assert_array_equal(stars["x"], [1.5, -0.5])
    np.testing.assert_array_equal(stars["y"], [2.25, 3.0])
    np.testing.assert_array_equal(stars["flux"], [100.0, 2000.0])


def test_the_canonical_name_wins_over_another_name_of_the_same_column(tmp_path):
    stars = read_star_list(_write(tmp_path, "xcentroid,x,y\n9,1,2\n"))
    assert stars["x"].tolist() == [1.0]


@pytest.mark.parametrize(("text", "match"), [
    ("u,v\n1,2\n", r"lacks required column.*x may also be named x_px.*col"),
    ("# u v\n1 2\n", r"lacks required column"),  # a comment that is not a header is not taken as one
    ("1.5,2.5\n3,4\n", r"first row holds numbers: start it with a header row"),
])
def test_lists_that_cannot_be_read_as_ours_say_why(tmp_path, text, match):
    with pytest.raises(InvalidInputError, match=match):
        read_star_list(_write(tmp_path, text))


def test_a_spreadsheets_unicode_text_reads_as_utf8_does(tmp_path):
    """Excel's "Unicode text": UTF-16 with its byte-order mark, tab-separated."""
    path = tmp_path / "stars.txt"
    path.write_bytes("x\ty\tflux\r\n1.5\t2.25\t100\r\n".encode("utf-16"))
    assert {k: v.tolist() for k, v in read_star_list(path).items()} == {"x": [1.5], "y": [2.25], "flux": [100.0]}
