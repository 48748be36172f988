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
