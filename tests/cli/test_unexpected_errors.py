"""An exception the commands do not expect (a fault of startrack's) is one line and exit status
3, not a traceback; STARTRACK_DEBUG=1 shows the traceback."""

from __future__ import annotations

import contextlib
import io

import pytest

from startrack.cli import _solve_stars_cmd, main


def _broken(argv):
    raise RuntimeError("a bug\nover two lines")


def test_an_unexpected_error_is_one_line_and_exit_3(monkeypatch):
    monkeypatch.setattr(_solve_stars_cmd, "main", _broken)
    monkeypatch.delenv("STARTRACK_DEBUG", raising=False)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["solve-stars", "list.csv"])
    assert code == 3 and out.getvalue() == ""
    assert err.getvalue() == ("startrack solve-stars: error: unexpected RuntimeError (a fault of startrack's, please "
                              "report it; STARTRACK_DEBUG=1 shows where): a bug over two lines\n")


def test_startrack_debug_shows_the_traceback(monkeypatch):
    monkeypatch.setattr(_solve_stars_cmd, "main", _broken)
    monkeypatch.setenv("STARTRACK_DEBUG", "1")
    with pytest.raises(RuntimeError, match="a bug"):
        main(["solve-stars", "list.csv"])


def test_a_plain_value_error_is_a_fault_of_ours_not_bad_input(monkeypatch):
    # bad input raises startrack's own errors (exit 2); a ValueError from numpy, astropy or a line of ours
    # that was not meant to see it means a check is missing, which is ours to fix (exit 3, not "misuse")
    def numpy_refuses(argv):
        raise ValueError("zero-size array to reduction operation minimum which has no identity")

    monkeypatch.setattr(_solve_stars_cmd, "main", numpy_refuses)
    monkeypatch.delenv("STARTRACK_DEBUG", raising=False)
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(["solve-stars", "list.csv"])
    assert code == 3 and "unexpected ValueError (a fault of startrack's" in err.getvalue()
